"""Compiled per-sensor loops over blocks of samples (Numba, CPU; sensors on all cores).

:func:`masked_block_means` (:func:`fogbayes.preprocess.blocks.group_mean`'s definition, one
shared clock) and :func:`stability` (B0 and Bs before/after, paper 004 eqs. 12-13), run as
:mod:`.kernels` by :func:`fogbayes.support.numba_cache.over_rows`.
"""

from __future__ import annotations

import numpy as np

from ..support.numba_cache import numba, over_rows


@numba.njit(cache=True, error_model="numpy", nogil=True)
def _block_means_range(s0, s1, t, y, z, use, start, stop, tm, ym, zm, cnt):
    c, nb = z.shape[1], start.size
    acc = np.empty(c)
    for s in range(s0, s1):
        for j in range(nb):
            a, b = start[j], stop[j]
            t0 = t[a]
            k = 0
            dt_used = 0.0
            dt_all = 0.0
            ysum = 0.0
            for q in range(c):
                acc[q] = 0.0
            for i in range(a, b):
                rel = t[i] - t0  # offsets from the block's first stamp: no Unix-time rounding
                dt_all += rel
                if use[s, i]:
                    k += 1
                    dt_used += rel
                    ysum += y[s, i]
                    for q in range(c):
                        acc[q] += z[s, q, i]
            cnt[s, j] = k
            tm[s, j] = t0 + (dt_used / k if k > 0 else dt_all / (b - a))
            ym[s, j] = ysum / k if k > 0 else np.nan
            for q in range(c):
                zm[s, q, j] = acc[q] / k if k > 0 else np.nan


def masked_block_means(t, y, z, use, start, stop):
    """Per sensor and block [start_j, stop_j) of the shared time stamps t (n,): mean time of
    the used samples (of all of them where none is used), mean of y (S, n) and of each
    covariate of z (S, c, n) over the used samples (NaN where none is), and their count.

    Returns tm (S, m), y (S, m), z (S, c, m), count (S, m) -- ``fit_blocks``' fields.
    """
    S, c = z.shape[0], z.shape[1]
    nb = start.size
    tm = np.empty((S, nb))
    ym = np.empty((S, nb))
    zm = np.empty((S, c, nb))
    cnt = np.zeros((S, nb), np.int64)
    over_rows(_block_means_range, S, t, y, z, use, start, stop, tm, ym, zm, cnt)
    return tm, ym, zm, cnt


@numba.njit(cache=True, error_model="numpy", nogil=True, fastmath={"reassoc", "contract"})
def _stability_range(s0, s1, before, after, a, b, start, stop, offsets, b0, bs):
    W = offsets.size - 1
    most = 0
    for w in range(W):
        most = max(most, offsets[w + 1] - offsets[w])
    means = np.empty(most)
    for s in range(s0, s1):
        for q in range(2):
            x = before if q == 0 else after
            tot = 0.0
            for i in range(a, b):
                tot += x[s, i]
            b0[q, s] = tot / (b - a)
            for w in range(W):
                j0, j1 = offsets[w], offsets[w + 1]
                k = j1 - j0
                if k < 2:
                    continue
                for j in range(k):
                    lo, hi = a + start[j0 + j], a + stop[j0 + j]
                    if hi - lo == 1:  # a block of one sample (1 s windows at 1 Hz)
                        means[j] = x[s, lo]
                        continue
                    acc = 0.0
                    for i in range(lo, hi):
                        acc += x[s, i]
                    means[j] = acc / (hi - lo)
                m = 0.0
                for j in range(k):
                    m += means[j]
                m /= k
                ss = 0.0
                for j in range(k):
                    ss += (means[j] - m) ** 2
                bs[q, s, w] = np.sqrt(ss / (k - 1))


def stability(before, after, a, b, start, stop, offsets):
    """Bias and bias stability of every row of ``before`` and ``after`` (S, n) on samples
    [a, b) (paper 004 eqs. 12-13): ``B0 = mean(x[a:b])`` and, per window w,
    ``Bs_w = std_{n-1}`` of the means of the blocks ``[a + start_j, a + stop_j)`` for j in
    ``offsets[w]:offsets[w + 1]``.

    Returns B0 (2, S) and Bs (2, S, W) (index 0: before, 1: after; NaN for a window of
    fewer than two blocks).
    """
    S = before.shape[0]
    W = offsets.size - 1
    b0 = np.empty((2, S))
    bs = np.full((2, S, W), np.nan)
    over_rows(_stability_range, S, before, after, int(a), int(b), start, stop, offsets,
                  b0, bs)
    return b0, bs
