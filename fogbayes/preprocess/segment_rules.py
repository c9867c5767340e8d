"""The soak/ramp segmenter's per-row rules, in plain Python (NumPy arrays, no Numba).

:func:`count_runs` counts a row's label runs; :func:`merge_row` labels samples (+1, -1, 0 by
``threshold``; a NaN rate is 0) and merges, shortest first, runs shorter than
``min_duration`` (duration = end of last - first time) into the neighbours' common label or
the longer neighbour's (left on a tie); :func:`stats_row`: mean temperature and
least-squares slope per run. One definition for both backends: run as they are for one
record (importing and loading Numba costs more than the loops, ~0.7 s of a ``fogbayes fit``),
compiled by :mod:`.segment_loops` for many rows.
"""

from __future__ import annotations

import numpy as np


def count_runs(rates, threshold) -> int:
    """Runs of equal labels in one row (before merging)."""
    n = 1
    prev = 1 if rates[0] > threshold else (-1 if rates[0] < -threshold else 0)
    for i in range(1, rates.shape[0]):
        cur = 1 if rates[i] > threshold else (-1 if rates[i] < -threshold else 0)
        n += cur != prev
        prev = cur
    return n


def merge_row(rates, threshold, t, end, min_duration, lab, start, stop):
    """Runs of one row's labels merged in place into lab/start/stop; returns their number."""
    n = rates.size
    r = 0
    prev = 1 if rates[0] > threshold else (-1 if rates[0] < -threshold else 0)
    lab[0], start[0] = prev, 0
    for i in range(1, n):
        cur = 1 if rates[i] > threshold else (-1 if rates[i] < -threshold else 0)
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


def stats_row(T, t, start, stop, count, mean, slope):
    """Mean of T (n,) and least-squares slope of T on t over each of ``count`` runs."""
    for k in range(count):
        a, b = start[k], stop[k]
        m = b - a
        tb, yb = 0.0, 0.0
        for i in range(a, b):
            tb += t[i]
            yb += T[i]
        tb /= m
        yb /= m
        mean[k] = yb
        if m < 2:
            continue
        sxy, sxx = 0.0, 0.0
        for i in range(a, b):
            dt = t[i] - tb
            sxy += dt * (T[i] - yb)
            sxx += dt * dt
        slope[k] = sxy / sxx


def merge_runs(rates, threshold, t, end, min_duration):
    """Merged runs of the labels of every row of rates (S, n): lab, start, stop (S, R) and
    count (S,) (R: the most runs of any row before merging)."""
    S = rates.shape[0]
    threshold, min_duration = float(threshold), float(min_duration)
    R = max(count_runs(rates[s], threshold) for s in range(S))
    lab = np.zeros((S, R), np.int64)
    start = np.zeros((S, R), np.int64)
    stop = np.zeros((S, R), np.int64)
    n = np.array([merge_row(rates[s], threshold, t, end, min_duration, lab[s], start[s],
                            stop[s]) for s in range(S)], np.int64)
    return lab, start, stop, n


def run_stats(T, t, start, stop, count):
    """Mean of T (S, n) and least-squares slope of T on t over each run: (S, R) each."""
    mean = np.zeros(start.shape)
    slope = np.zeros(start.shape)
    for s in range(start.shape[0]):
        stats_row(T[s], t, start[s], stop[s], int(count[s]), mean[s], slope[s])
    return mean, slope
