"""Compiled loops of the soak/ramp segmenter (Numba): run merging and per-segment statistics.

:func:`merge_runs` labels samples (+1, -1, 0 by ``threshold``) and merges, shortest first, runs
shorter than ``min_duration`` (duration = end of last - first time) into the neighbours' common
label or the longer neighbour's (left on a tie); rows on threads
(:func:`fogbayes.support.numba_cache.over_rows`). :func:`run_stats`: mean temperature and
least-squares slope per segment.
"""

from __future__ import annotations

import numpy as np

from ..support.numba_cache import numba, over_rows

#: rows from which the loops run on all cores
MIN_ROWS = 8


@numba.njit(cache=True, inline="always")
def _label(rate, threshold):
    """1 (ramp up), -1 (ramp down) or 0 (soak; also a NaN rate)."""
    return 1 if rate > threshold else (-1 if rate < -threshold else 0)


@numba.njit(cache=True)
def _merge_row(rates, threshold, t, end, min_duration, lab, start, stop):
    """Runs of one row's labels merged in place into lab/start/stop; returns their number."""
    n = rates.size
    r = 0
    prev = _label(rates[0], threshold)
    lab[0], start[0] = prev, 0
    for i in range(1, n):
        cur = _label(rates[i], threshold)
        if cur != prev:
            stop[r] = i
            r += 1
            lab[r], start[r] = cur, i
            prev = cur
    stop[r] = n
    r += 1
    d = np.empty(r)
    while r > 1:
        i = 0
        for k in range(r):
            d[k] = end[stop[k] - 1] - t[start[k]]
            if d[k] < d[i]:
                i = k
        if d[i] >= min_duration:
            break
        if 0 < i < r - 1 and lab[i - 1] == lab[i + 1]:
            lab[i] = lab[i - 1]
        elif i == 0 or (i + 1 < r and d[i + 1] > d[i - 1]):
            lab[i] = lab[i + 1]
        else:
            lab[i] = lab[i - 1]
        w = 0  # join neighbours that now share a label
        for k in range(1, r):
            if lab[k] == lab[w]:
                stop[w] = stop[k]
            else:
                w += 1
                lab[w], start[w], stop[w] = lab[k], start[k], stop[k]
        r = w + 1
    return r


@numba.njit(cache=True, nogil=True)
def _count_range(s0, s1, rates, threshold, first):
    for s in range(s0, s1):
        prev = _label(rates[s, 0], threshold)
        for i in range(1, rates.shape[1]):
            cur = _label(rates[s, i], threshold)
            first[s] += cur != prev
            prev = cur


@numba.njit(cache=True, nogil=True)
def _merge_range(s0, s1, rates, threshold, t, end, min_duration, lab, start, stop, count):
    for s in range(s0, s1):
        count[s] = _merge_row(rates[s], threshold, t, end, min_duration, lab[s], start[s],
                              stop[s])


def merge_runs(rates, threshold, t, end, min_duration):
    """Merged runs of the labels of every row of rates (S, n): lab, start, stop (S, R) and
    count (S,) (R: the most runs of any row before merging)."""
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
        for k in range(count[s]):
            a, b = start[s, k], stop[s, k]
            m = b - a
            tb, yb = 0.0, 0.0
            for i in range(a, b):
                tb += t[i]
                yb += T[s, i]
            tb /= m
            yb /= m
            mean[s, k] = yb
            if m < 2:
                continue
            sxy, sxx = 0.0, 0.0
            for i in range(a, b):
                dt = t[i] - tb
                sxy += dt * (T[s, i] - yb)
                sxx += dt * dt
            slope[s, k] = sxy / sxx


def run_stats(T, t, start, stop, count):
    """Mean of T (S, n) and least-squares slope of T on t over each run: (S, R) each."""
    mean = np.zeros(start.shape)
    slope = np.zeros(start.shape)
    over_rows(_stats_range, start.shape[0], T, t, start, stop, count, mean, slope,
              min_rows=MIN_ROWS)
    return mean, slope
