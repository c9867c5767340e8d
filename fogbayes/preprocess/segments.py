"""Segmentation of a thermal test into soaks and ramps.

Labels by the Savitzky-Golay rate r over ``smooth_s`` (:mod:`.temperature_rate`): soak
|r| <= ``rate_threshold``, ramp_up r > it, ramp_down r < -it; runs shorter than ``min_duration``
merged shortest first. Boundaries are fuzzy by ~``smooth_s / 2``; not cut at gaps.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..errors import FogbayesError
from ._checks import (
    GAP_FACTOR,
    as_1d,
    check_time,
    check_window,
    median_step,
    same_length,
)
from .temperature_rate import temperature_rate

#: below this many samples (rows x length) the rules run as plain Python
#: (:mod:`.segment_rules`, ~10 us a sample); above, compiled (:mod:`.segment_loops`), whose
#: import and cache load cost ~0.7 s (measured on the 2-core box: 3 600 samples 3 ms in
#: Python; 227 000 samples 2.2 s)
PYTHON_BELOW = 50_000

_KINDS = {0: "soak", 1: "ramp_up", -1: "ramp_down"}


class Segment(NamedTuple):
    """A soak or a ramp: samples ``start:stop`` (stop exclusive), times of its first and
    last sample, mean temperature (deg C), and least-squares temperature slope (deg C/s)."""

    kind: str
    start: int
    stop: int
    t_start: float
    t_stop: float
    mean_temperature: float
    mean_rate: float


def segment_thermal(time, temperature, *, rate_threshold: float = 0.1 / 60.0,
                    min_duration: float = 300.0, smooth_s: float = 60.0,
                    gap_factor: float = GAP_FACTOR) -> list[Segment]:
    """Split a thermal test into soaks and ramps (see the module doc).

    Args:
        time: (n,) s.
        temperature: (n,) deg C.
        rate_threshold: deg C/s separating soaks from ramps (default 0.1 deg C/min; paper
            004 ramps at 0.5 deg C/min).
        min_duration: shortest segment kept (s).
        smooth_s: window of the temperature-rate smoother (s).

    Returns:
        Segments in time order, covering every sample once.
    """
    T = as_1d(temperature, "temperature")
    return segment_thermal_rows(time, T[None, :], rate_threshold=rate_threshold,
                                min_duration=min_duration, smooth_s=smooth_s,
                                gap_factor=gap_factor)[0]


def segment_thermal_rows(time, temperatures, *, rate_threshold: float = 0.1 / 60.0,
                         min_duration: float = 300.0, smooth_s: float = 60.0,
                         gap_factor: float = GAP_FACTOR) -> list[list[Segment]]:
    """:func:`segment_thermal` of several sensors sampled at ``time``: (sensors, n) deg C.

    The smoothed rates of all sensors come from one filter call; labels are merged and each
    segment's mean and slope computed by :mod:`.segment_rules` (compiled for large inputs).
    """
    t = check_time(time)
    T = np.asarray(temperatures, dtype=float)
    if T.ndim != 2 or T.shape[0] == 0:
        raise FogbayesError(f"temperatures must be (sensors, n) with a sensor or more, got "
                            f"shape {T.shape}", column="temperature",
                            fix="pass one row per sensor")
    same_length(time=t, temperature=T[0])
    if not np.isfinite(rate_threshold) or rate_threshold <= 0:
        raise FogbayesError(f"rate_threshold must be positive, got {rate_threshold!r}",
                            column="rate_threshold",
                            fix="pass e.g. rate_threshold=0.1/60 (deg C/s)")
    check_window(smooth_s, t, name="smooth_s")
    rates = temperature_rate(t, T, method="savgol", window_s=smooth_s, polyorder=1,
                             gap_factor=gap_factor)
    end = np.r_[t[1:], t[-1] + median_step(t)] if t.size > 1 else t + 1.0
    if T.size < PYTHON_BELOW:
        from . import segment_rules as loops
    else:
        from . import segment_loops as loops
    lab, start, stop, count = loops.merge_runs(rates, float(rate_threshold), t, end,
                                               float(min_duration))
    R = int(count.max())
    lab, start, stop = lab[:, :R], start[:, :R], stop[:, :R]
    mean, slope = loops.run_stats(T, t, start, stop, count)
    lab, start, stop, mean, slope = (x.tolist() for x in (lab, start, stop, mean, slope))
    tl = t.tolist()
    return [[Segment(_KINDS[lab[s][k]], start[s][k], stop[s][k], tl[start[s][k]],
                     tl[stop[s][k] - 1], mean[s][k], slope[s][k]) for k in range(c)]
            for s, c in enumerate(count.tolist())]
