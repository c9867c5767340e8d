"""The soak/ramp segmenter's rules (:mod:`.segment_rules`) compiled by Numba, rows on threads
(:func:`fogbayes.support.numba_cache.over_rows`): the backend for many rows or long records.
"""

from __future__ import annotations

import numpy as np

from ..support.numba_cache import numba, over_rows
from . import segment_rules as rules

#: rows from which the loops run on all cores
MIN_ROWS = 8

_count = numba.njit(cache=True, nogil=True)(rules.count_runs)
_merge_row = numba.njit(cache=True, nogil=True)(rules.merge_row)
_stats_row = numba.njit(cache=True, nogil=True)(rules.stats_row)


@numba.njit(cache=True, nogil=True)
def _count_range(s0, s1, rates, threshold, first):
    for s in range(s0, s1):
        first[s] = _count(rates[s], threshold)


@numba.njit(cache=True, nogil=True)
def _merge_range(s0, s1, rates, threshold, t, end, min_duration, lab, start, stop, count):
    for s in range(s0, s1):
        count[s] = _merge_row(rates[s], threshold, t, end, min_duration, lab[s], start[s],
                              stop[s])


def merge_runs(rates, threshold, t, end, min_duration):
    """:func:`fogbayes.preprocess.segment_rules.merge_runs`, compiled."""
    S = rates.shape[0]
    threshold, min_duration = float(threshold), float(min_duration)
    first = np.ones(S, np.int64)  # runs before merging: the arrays' width
    over_rows(_count_range, S, rates, threshold, first, min_rows=MIN_ROWS)
    R = int(first.max())
    lab = np.zeros((S, R), np.int64)
    start = np.zeros((S, R), np.int64)
    stop = np.zeros((S, R), np.int64)
    count = np.zeros(S, np.int64)
    over_rows(_merge_range, S, rates, threshold, t, end, min_duration, lab, start, stop, count,
              min_rows=MIN_ROWS)
    return lab, start, stop, count


@numba.njit(cache=True, nogil=True)
def _stats_range(s0, s1, T, t, start, stop, count, mean, slope):
    for s in range(s0, s1):
        _stats_row(T[s], t, start[s], stop[s], count[s], mean[s], slope[s])


def run_stats(T, t, start, stop, count):
    """:func:`fogbayes.preprocess.segment_rules.run_stats`, compiled."""
    mean = np.zeros(start.shape)
    slope = np.zeros(start.shape)
    over_rows(_stats_range, start.shape[0], T, t, start, stop, count, mean, slope,
              min_rows=MIN_ROWS)
    return mean, slope
