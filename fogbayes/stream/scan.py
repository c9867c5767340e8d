"""Sampling facts of a large recording from its time column: exact median step, gaps, runs.

The median of the steps by radix selection (:func:`.select.stream_median`, as ``np.median``);
one more pass records the gaps (:func:`fogbayes.preprocess._checks.segment_bounds`' rule) and,
per run, its rows, first time and min/max/mean step. Memory O(runs).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from ..errors import TooShortError
from ..preprocess._checks import GAP_FACTOR
from .select import stream_median
from .sources import DEFAULT_ROWS, RecordSource


class TimeScan(NamedTuple):
    """What the in-memory code would compute from the whole time column.

    ``bounds``: run start rows plus ``n`` at the end (as ``segment_bounds``); per run:
    ``run_t0`` first time, ``run_t_last`` last time, ``run_dt_min``/``run_dt_max``/
    ``run_dt_mean`` of its steps (NaN for a one-sample run).
    """

    n: int
    t_first: float
    t_last: float
    dt_median: float
    dt_min: float
    dt_max: float
    gap_factor: float
    bounds: np.ndarray
    run_t0: np.ndarray
    run_t_last: np.ndarray
    run_dt_min: np.ndarray
    run_dt_max: np.ndarray
    run_dt_mean: np.ndarray
    passes: int

    @property
    def sample_rate(self) -> float:
        return 1.0 / self.dt_median

    @property
    def t_absmax(self) -> float:
        return max(abs(self.t_first), abs(self.t_last))


def _steps(source: RecordSource, rows: int):
    """The time steps, chunk by chunk (step i lies between rows i-1 and i)."""
    last = None
    for ch in source.chunks(rows, fields=("time",)):
        t = ch.time
        dt = np.diff(t) if last is None else np.diff(t, prepend=last)
        last = float(t[-1])
        if dt.size:
            yield dt


def scan_time(source: RecordSource, *, rows: int = DEFAULT_ROWS,
              gap_factor: float = GAP_FACTOR) -> TimeScan:
    """Scan the time column of ``source`` (validated on the way: finite, increasing)."""
    source.require("time")
    if source.n < 2:
        raise TooShortError(f"needs at least 2 samples, got {source.n}", file=source.source,
                            column=source.time_name, fix="pass a longer record")
    med, passes = stream_median(lambda: _steps(source, rows), source.n - 1)
    limit = gap_factor * med
    starts, t0s, tl, mins, maxs, sums, counts = [0], [], [], [], [], [], []
    cur = {"min": np.inf, "max": -np.inf, "sum": [], "count": 0}
    t_first = t_last = None
    dt_min, dt_max = np.inf, -np.inf

    def close_run(last_t):
        tl.append(last_t)
        mins.append(cur["min"] if cur["count"] else np.nan)
        maxs.append(cur["max"] if cur["count"] else np.nan)
        sums.append(math.fsum(cur["sum"]))
        counts.append(cur["count"])

    prev_t = None
    for ch in source.chunks(rows, fields=("time",)):
        t = ch.time
        if t_first is None:
            t_first = float(t[0])
            t0s.append(t_first)
        dt = np.diff(t) if prev_t is None else np.diff(t, prepend=prev_t)
        first = ch.start + (1 if prev_t is None else 0)
        tt = t if prev_t is None else np.concatenate([[prev_t], t])  # tt[i] = row first-1+i
        if dt.size:
            dt_min, dt_max = min(dt_min, float(dt.min())), max(dt_max, float(dt.max()))
        cuts = np.flatnonzero(dt > limit)
        a = 0
        for c in list(cuts) + [dt.size]:
            part = dt[a:c]
            if part.size:
                cur["min"] = min(cur["min"], float(part.min()))
                cur["max"] = max(cur["max"], float(part.max()))
                cur["sum"].append(float(np.sum(part)))
                cur["count"] += part.size
            if c < dt.size:  # a gap before row first + c
                close_run(float(tt[c]))
                starts.append(first + int(c))
                t0s.append(float(tt[c + 1]))
                cur = {"min": np.inf, "max": -np.inf, "sum": [], "count": 0}
            a = c + 1
        prev_t = t_last = float(t[-1])
    close_run(t_last)
    counts = np.asarray(counts, float)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = np.where(counts > 0, np.asarray(sums) / np.maximum(counts, 1), np.nan)
    return TimeScan(source.n, t_first, t_last, med, dt_min, dt_max, float(gap_factor),
                    np.asarray(starts + [source.n], dtype=np.int64), np.asarray(t0s),
                    np.asarray(tl), np.asarray(mins), np.asarray(maxs), mean, passes + 1)
