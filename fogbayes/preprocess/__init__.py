"""Preprocessing: pure functions on Recordings and arrays (NumPy).

* outliers      :func:`pauta_flags` (iterated 3-sigma, paper 004), :func:`hampel_flags`,
                :func:`mad_flags`, :func:`flag_outliers` -> :class:`OutlierFlags` (flags only,
                nothing is ever deleted)
* blocks        :func:`block_average` (any window, cut at gaps, time stamps = block means)
* paper004      :func:`paper004_smoothing` (rate 1 s, temperature 10 s on the 1 s grid)
* temperature   :func:`temperature_rate` (deg C/s; "difference" as paper 004 or "savgol")
* segments      :func:`segment_thermal` (soaks and ramps), :func:`segment_rate_table`
                (plateaus (T_i, Omega_j))
* detrend       :func:`detrend` (polynomial on a centred, scaled time basis)
"""

from .blocks import BlockAverage, BlockedRecording, BlockIndex, block_average, block_index
from .detrend import Detrended, detrend
from .outliers import OutlierFlags, flag_outliers, hampel_flags, mad_flags, pauta_flags
from .paper004 import Paper004Smoothed, paper004_smoothing
from .rate_table import RateCell, RateTable, segment_rate_table
from .segments import Segment, segment_thermal
from .temperature_rate import temperature_rate, temperature_rate_per_min

__all__ = [
    "BlockAverage", "BlockIndex", "BlockedRecording", "Detrended", "OutlierFlags",
    "Paper004Smoothed", "RateCell", "RateTable", "Segment", "block_average", "block_index",
    "detrend", "flag_outliers", "hampel_flags", "mad_flags", "paper004_smoothing",
    "pauta_flags", "segment_rate_table", "segment_thermal", "temperature_rate",
    "temperature_rate_per_min",
]
