"""Preprocessing: pure functions on Recordings and arrays (NumPy); outliers are flagged, never deleted.

Outliers :func:`pauta_flags`, :func:`hampel_flags`, :func:`mad_flags`, :func:`flag_outliers`;
blocks :func:`block_average`; :func:`paper004_smoothing`; :func:`temperature_rate` (deg C/s);
:func:`segment_thermal`, :func:`segment_rate_table`; :func:`detrend`.
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
