r"""Compiled sums behind TOTDEV, MTOTDEV and Theo1 (Numba, CPU, one pass per cluster size).

On the phase in samples :math:`S_k = \sum_{j<k}(y_j - \bar y)` (units of ``y`` squared):
TOTDEV (SP 1065 eq. 25) :math:`\sum_{i=1}^{N-2}(x^*_{i-m} - 2x^*_i + x^*_{i+m})^2` on the reflected
phase, O(N); MTOTDEV (eq. 27) per subsequence from a double-double prefix sum of the phase, using
the reflection symmetries of :math:`w_j`, O(N m); Theo1 (eq. 30)
:math:`\sum_i\sum_{k=1}^{m/2}(S_i - S_{i+k} - S_{i+m-k} + S_{i+m})^2/k`, in blocks of :data:`BLOCK`.
Pieces of squares are added with Neumaier compensation.
"""

from __future__ import annotations

import numpy as np

from ..support.numba_cache import numba

__all__ = ["mtotvar_sums", "phase_samples", "prefix2", "theo1_sums", "totvar_sums"]

BLOCK = 2048  # Theo1: phase points per block (the four read streams stay in L1)
PIECE = 8192  # TOTDEV: terms per compensated addition
_FAST = {"reassoc", "contract"}  # sums of squares only: SIMD order, NaN/inf semantics kept


@numba.njit(cache=True, inline="always")
def _add(acc, x):
    """Neumaier step: returns the new (sum, compensation) of ``acc = (s, c)`` plus ``x``."""
    s, c = acc
    t = s + x
    if abs(s) >= abs(x):
        c += (s - t) + x
    else:
        c += (x - t) + s
    return t, c


@numba.njit(cache=True, nogil=True)
def phase_samples(y, ref):
    """Phase in samples: ``S[0] = 0``, ``S[k] = sum_{j<k} (y[j] - ref)`` (n + 1 points)."""
    n = y.shape[0]
    S = np.empty(n + 1)
    s = 0.0
    S[0] = 0.0
    for i in range(n):
        s += y[i] - ref
        S[i + 1] = s
    return S


# ---------------------------------------------------------------------------------- TOTDEV

@numba.njit(cache=True, fastmath=_FAST)
def _sumsq_d2(a, b, c):
    acc = 0.0
    for i in range(b.shape[0]):
        d = (a[i] + c[i]) - 2.0 * b[i]
        acc += d * d
    return acc


@numba.njit(cache=True, inline="always")
def _xstar(S, k, last):
    """Phase reflected about both ends (SP 1065 eq. 25): x*_k for -(last-1) <= k <= 2 last - 1."""
    if k < 0:
        return 2.0 * S[0] - S[-k]
    if k > last:
        return 2.0 * S[last] - S[2 * last - k]
    return S[k]


@numba.njit(cache=True)
def _edge_terms(S, m, lo, hi, last):
    acc = 0.0
    for i in range(lo, hi + 1):
        d = (_xstar(S, i - m, last) + _xstar(S, i + m, last)) - 2.0 * S[i]
        acc += d * d
    return acc


@numba.njit(cache=True, nogil=True)
def totvar_sums(S, ms, out):
    """``out[t] = sum_{i=1}^{N-2} (x*_{i-m} - 2 x*_i + x*_{i+m})^2`` for ``m = ms[t]``
    (``1 <= m <= N - 1``)."""
    last = S.shape[0] - 1
    for t in range(ms.shape[0]):
        m = ms[t]
        a = max(1, m)  # interior: i - m >= 0 and i + m <= last
        b = min(last - 1, last - m)
        acc = (0.0, 0.0)
        if a <= b:
            for p in range(a, b + 1, PIECE):
                q = min(p + PIECE, b + 1)
                acc = _add(acc, _sumsq_d2(S[p - m:q - m], S[p:q], S[p + m:q + m]))
            acc = _add(acc, _edge_terms(S, m, 1, a - 1, last))
            acc = _add(acc, _edge_terms(S, m, b + 1, last - 1, last))
        else:
            acc = _add(acc, _edge_terms(S, m, 1, last - 1, last))
        out[t] = acc[0] + acc[1]


# --------------------------------------------------------------------------------- MTOTDEV

@numba.njit(cache=True, nogil=True)
def prefix2(S):
    """Compensated prefix sums of ``S``: ``P[t] = hi[t] + lo[t] = sum_{k<t} S[k]``."""
    N = S.shape[0]
    hi = np.empty(N + 1)
    lo = np.empty(N + 1)
    s = 0.0
    c = 0.0
    hi[0] = 0.0
    lo[0] = 0.0
    for k in range(N):
        x = S[k]
        t = s + x
        bp = t - s
        c += (s - (t - bp)) + (x - bp)  # TwoSum error of s + x
        s = t
        hi[k + 1] = s
        lo[k + 1] = c
    return hi, lo


@numba.njit(cache=True)
def _local_prefix(hi, lo, i, n3, s0, slope, c, r):
    """``c[t]`` (t = 0..3m) of subsequence ``i`` and its reverse ``r[t] = c[3m - t]``."""
    h0 = hi[i]
    l0 = lo[i]
    hs = hi[i:i + n3 + 1]
    ls = lo[i:i + n3 + 1]
    for t in range(n3 + 1):
        ft = float(t)
        c[t] = ((hs[t] - h0) + (ls[t] - l0)) - ft * s0 - slope * (0.5 * ft * (ft - 1.0))
    for t in range(n3 + 1):
        r[t] = c[n3 - t]


@numba.njit(cache=True, fastmath=_FAST)
def _w_pairs_a(c0, r2, r1, r0, ca, cb, C, lo, hi):
    """Left and right terms for j = lo..hi <= m (module doc, regions A):
    w = c[j] + 3 (c[m-j] - c[2m-j]) + c[3m-j],  w' = 2C - c[3m-j] - 3 (c[2m+j] - c[m+j]) - c[j]."""
    acc = 0.0
    for j in range(lo, hi + 1):
        wl = c0[j] + 3.0 * (r2[j] - r1[j]) + r0[j]
        wr = (2.0 * C - r0[j]) - 3.0 * (ca[j] - cb[j]) - c0[j]
        acc += wl * wl + wr * wr
    return acc


@numba.njit(cache=True, fastmath=_FAST)
def _w_pairs_b(c0, cm, r1, r0, rm, cb, C, lo, hi):
    """Regions B (m < j <= 3m/2): w = c[j] - 3 (c[j-m] + c[2m-j]) + c[3m-j],
    w' = -4C - c[3m-j] + 3 (c[4m-j] + c[m+j]) - c[j]."""
    acc = 0.0
    for j in range(lo, hi + 1):
        wl = c0[j] - 3.0 * (cm[j] + r1[j]) + r0[j]
        wr = (-4.0 * C - r0[j]) + 3.0 * (rm[j] + cb[j]) - c0[j]
        acc += wl * wl + wr * wr
    return acc


@numba.njit(cache=True, nogil=True)
def mtotvar_sums(S, hi, lo, ms, out):
    """``out[t] = sum_i sum_{j<6m} w_ij^2`` (module doc) for ``m = ms[t]`` (``3m <= N``)."""
    N = S.shape[0]
    for t in range(ms.shape[0]):
        m = ms[t]
        n3 = 3 * m
        half = n3 // 2
        dist = 1.5 * m if n3 % 2 == 0 else 0.5 * (n3 + 1)
        J = (n3 - 1) // 2  # j = 1..J pair with 3m - j; j = 3m/2 (m even) is its own pair
        c = np.empty(n3 + 1)
        r = np.empty(n3 + 1)
        acc = (0.0, 0.0)
        for i in range(N - n3 + 1):
            mean1 = ((hi[i + half] - hi[i]) + (lo[i + half] - lo[i])) / half
            mean2 = ((hi[i + n3] - hi[i + n3 - half]) + (lo[i + n3] - lo[i + n3 - half])) / half
            slope = (mean2 - mean1) / dist
            _local_prefix(hi, lo, i, n3, S[i], slope, c, r)
            C = c[n3]
            w0 = C + 3.0 * (c[m] - c[2 * m])  # w_0 = w'_0
            s = 2.0 * w0 * w0
            jA = min(m, J)
            # every read is a view indexed by j >= 0 (SIMD, no wraparound test):
            # A: c[m-j] = r[2m+j], c[2m-j] = r[m+j], c[3m-j] = r[j]
            if jA >= 1:
                s += 2.0 * _w_pairs_a(c, r[2 * m:], r[m:], r, c[2 * m:], c[m:], C, 1, jA)
            if J > m:  # B, indexed by j' = j - m: c[j] = c[m+j'], c[2m-j] = r[2m+j'], ...
                s += 2.0 * _w_pairs_b(c[m:], c, r[2 * m:], r[m:], r, c[2 * m:], C,
                                      1, J - m)
            if n3 % 2 == 0:
                j = half  # m even: j = 3m/2 lies in region B
                wl = c[j] - 3.0 * (c[j - m] + r[m + j]) + r[j]
                wr = (-4.0 * C - r[j]) + 3.0 * (r[j - m] + c[m + j]) - c[j]
                s += wl * wl + wr * wr
            acc = _add(acc, s)
        out[t] = acc[0] + acc[1]


# ----------------------------------------------------------------------------------- Theo1

@numba.njit(cache=True, fastmath=_FAST)
def _theo1_block(s0, sk, smk, sm):
    acc = 0.0
    for i in range(s0.shape[0]):
        d = (s0[i] - sk[i]) + (sm[i] - smk[i])
        acc += d * d
    return acc


@numba.njit(cache=True, nogil=True)
def theo1_sums(S, ms, out):
    """``out[t] = sum_{i<N-m} sum_{k=1}^{m/2} (S_i - S_{i+k} - S_{i+m-k} + S_{i+m})^2 / k``
    for even ``m = ms[t]`` (``2 <= m <= N - 1``)."""
    N = S.shape[0]
    for t in range(ms.shape[0]):
        m = ms[t]
        h = m // 2
        L = N - m
        acc = (0.0, 0.0)
        for i0 in range(0, L, BLOCK):
            b = min(BLOCK, L - i0)
            s0 = S[i0:i0 + b]
            sm = S[i0 + m:i0 + m + b]
            part = 0.0
            for k in range(1, h + 1):
                part += _theo1_block(s0, S[i0 + k:i0 + k + b], S[i0 + m - k:i0 + m - k + b],
                                     sm) / k
            acc = _add(acc, part)
        out[t] = acc[0] + acc[1]
