r"""Modified Allan and overlapping Hadamard variances of rate data in fused compiled loops (Numba).

With phase :math:`S_k = \sum_{j<k}(y_j - \bar y)`, :math:`d_i = S_{i+2m} - 2S_{i+m} + S_i`,
:math:`h_i = d_{i+m} - d_i`:
:math:`H\sigma^2_O(m) = \sum_{i<L} h_i^2 / (6 m^2 L)`, ``L = N - 3m``;
:math:`\mathrm{Mod}\,\sigma^2(m) = \sum_{j<L} v_j^2 / (2 m^4 L)`, :math:`v_j = \sum_{i=j}^{j+m-1} d_i`,
``L = N - 3m + 1`` (NIST SP 1065 eqs. 14, 18); :math:`v_{j+1} = v_j + h_j`, interleaved in four
segments. Units of ``y`` squared. Non-finite samples are gaps: terms touching one are excluded
(``count`` = kept; none kept gives NaN), as ``allan_variance(..., gaps=True)``.
"""

from __future__ import annotations

import numpy as np

from ..support.numba_cache import numba

__all__ = ["mod_hadamard_variance"]

CHUNK = 2048  # terms whose h are formed before they are summed (buffers stay in L1)
_FAST = {"reassoc", "contract"}  # sums of squares only: SIMD order, NaN/inf semantics kept


@numba.njit(cache=True, nogil=True)
def _phase(y, ref, gaps):
    """Phase ``S`` (n + 1 points; non-finite samples add 0) and, with ``gaps``, the prefix
    count ``G`` of non-finite samples (else a placeholder of length 1)."""
    n = y.shape[0]
    S = np.empty(n + 1)
    G = np.zeros(n + 1 if gaps else 1, np.int64)
    s = 0.0
    S[0] = 0.0
    if not gaps:
        for i in range(n):
            s += y[i] - ref
            S[i + 1] = s
        return S, G
    g = 0
    for i in range(n):
        v = y[i]
        if np.isfinite(v):
            s += v - ref
        else:
            g += 1
        S[i + 1] = s
        G[i + 1] = g
    return S, G


@numba.njit(cache=True, inline="always")
def _h(s0, s1, s2, s3, k):
    """Third difference (A_{i+2m} - A_{i+m}) - (A_{i+m} - A_i), A the block sums."""
    a0 = s1[k] - s0[k]
    a1 = s2[k] - s1[k]
    a2 = s3[k] - s2[k]
    return (a2 - a1) - (a1 - a0)


@numba.njit(cache=True, nogil=True)
def _v0(S, j, m):
    """Inner sum v_j = sum_{i=j}^{j+m-1} d_i, summed directly in four partial sums."""
    s0, s1, s2 = S[j:j + m], S[j + m:j + 2 * m], S[j + 2 * m:j + 3 * m]
    q = m - m % 4
    a0 = a1 = a2 = a3 = 0.0
    for i in range(0, q, 4):
        a0 += (s2[i] - s1[i]) - (s1[i] - s0[i])
        a1 += (s2[i + 1] - s1[i + 1]) - (s1[i + 1] - s0[i + 1])
        a2 += (s2[i + 2] - s1[i + 2]) - (s1[i + 2] - s0[i + 2])
        a3 += (s2[i + 3] - s1[i + 3]) - (s1[i + 3] - s0[i + 3])
    for i in range(q, m):
        a0 += (s2[i] - s1[i]) - (s1[i] - s0[i])
    return (a0 + a1) + (a2 + a3)


@numba.njit(cache=True, nogil=True)
def _hfill(S, j, m, out, c):
    """``out[k] = h_{j+k}`` for k < c (elementwise, strict IEEE: SIMD without reordering)."""
    s0, s1 = S[j:j + c], S[j + m:j + m + c]
    s2, s3 = S[j + 2 * m:j + 2 * m + c], S[j + 3 * m:j + 3 * m + c]
    for k in range(c):
        out[k] = _h(s0, s1, s2, s3, k)


@numba.njit(cache=True, fastmath=_FAST)
def _sumsq(x):
    """Sum of squares, reassociated into SIMD lanes (only the order of the sum changes)."""
    acc = 0.0
    for i in range(x.shape[0]):
        acc += x[i] * x[i]
    return acc


@numba.njit(cache=True, fastmath=_FAST)
def _sumsq_kept(x, g_end, g_start):
    """Sum of squares of the terms touching no gap (``g_end == g_start``) and their number."""
    acc = 0.0
    kept = 0
    for i in range(x.shape[0]):
        ok = g_end[i] == g_start[i]
        acc += x[i] * x[i] if ok else 0.0
        kept += 1 if ok else 0
    return acc, kept


@numba.njit(cache=True, nogil=True)
def _add_terms(x, j, span, G, gaps, out, t):
    """Add the squares of terms ``x`` (term index j, j+1, ...) to ``out[0][t]``, counts to
    ``out[1][t]``; a term spanning phase points j .. j+span is kept if no sample is NaN."""
    if not gaps or G[j + x.shape[0] - 1 + span] == G[j]:
        out[0][t] += _sumsq(x)
        out[1][t] += x.shape[0]
    else:
        c = x.shape[0]
        acc, kept = _sumsq_kept(x, G[j + span:j + span + c], G[j:j + c])
        out[0][t] += acc
        out[1][t] += kept


@numba.njit(cache=True, nogil=True)
def _mdev_sums(S, G, ms, gaps, sums, counts):
    """v_j for j < 4 seg by four interleaved running sums over the segments
    [p seg, (p+1) seg), each started by a direct sum; the (< 4) last terms directly."""
    N = S.shape[0]
    buf = np.empty((4, CHUNK))
    out = (sums, counts)
    for t in range(ms.shape[0]):
        m = ms[t]
        L = N - 3 * m + 1
        span = 3 * m - 1
        seg = L // 4
        v0, v1, v2, v3 = _v0(S, 0, m), _v0(S, seg, m), _v0(S, 2 * seg, m), _v0(S, 3 * seg, m)
        h0, h1, h2, h3 = buf[0], buf[1], buf[2], buf[3]
        for k0 in range(0, seg, CHUNK):
            c = min(CHUNK, seg - k0)
            ch = c if k0 + c < seg else c - 1  # a lane's last h is not needed (may lie past S)
            for p in range(4):
                _hfill(S, p * seg + k0, m, buf[p], ch)
                buf[p, c - 1] = buf[p, c - 1] if ch == c else 0.0
            for k in range(c):  # h -> v in place: four independent dependency chains
                x0, x1, x2, x3 = h0[k], h1[k], h2[k], h3[k]
                h0[k], h1[k], h2[k], h3[k] = v0, v1, v2, v3
                v0 += x0
                v1 += x1
                v2 += x2
                v3 += x3
            for p in range(4):
                _add_terms(buf[p, :c], p * seg + k0, span, G, gaps, out, t)
        for j in range(4 * seg, L):
            buf[0, 0] = _v0(S, j, m)
            _add_terms(buf[0, :1], j, span, G, gaps, out, t)


@numba.njit(cache=True, nogil=True)
def _ohdev_sums(S, G, ms, gaps, sums, counts):
    N = S.shape[0]
    buf = np.empty(CHUNK)
    out = (sums, counts)
    for t in range(ms.shape[0]):
        m = ms[t]
        L = N - 3 * m
        for j in range(0, L, CHUNK):
            c = min(CHUNK, L - j)
            _hfill(S, j, m, buf, c)
            _add_terms(buf[:c], j, 3 * m, G, gaps, out, t)


def mod_hadamard_variance(y, ms, kind: str) -> tuple[np.ndarray, np.ndarray]:
    """``(var, count)`` of ``kind`` ``"mdev"`` or ``"ohdev"`` at cluster sizes ``ms``.

    Args:
        y: rate samples, 1-D float64; NaN marks a missing sample: every term touching one
            is excluded, as ``allan_variance(y, ms, kind=kind, gaps=True)`` (which is also
            what a record without NaN gives with ``gaps=False``). +-inf is treated like NaN
            here (as that kernel with ``gaps=True``); ``allan_deviation`` rejects it earlier.
        ms: cluster sizes (ints), each with at least one term: ``3 m <= n`` (ohdev),
            ``3 m <= n + 1`` (mdev).
        kind: ``"mdev"`` (modified Allan) or ``"ohdev"`` (overlapping Hadamard).

    Returns:
        ``var`` and ``count`` (float arrays of shape ``(len(ms),)``), equal to
        :func:`~fogbayes.stats.allan_kernels.allan_variance` to rounding (about 1e-12
        relative). ``var`` is NaN where every term touches a gap (count 0).

    Raises:
        ValueError: unknown ``kind``, ``y`` not 1-D, no finite sample, or an ``m`` with
            no term.
    """
    if kind not in ("mdev", "ohdev"):
        raise ValueError(f"kind must be 'mdev' or 'ohdev', got {kind!r}")
    y = np.ascontiguousarray(y, dtype=np.float64)
    if y.ndim != 1:
        raise ValueError(f"y must be 1-D, got shape {y.shape}")
    ms_arr = np.asarray(ms, dtype=np.int64).reshape(-1)
    n = y.shape[0]
    top = (n + 1) // 3 if kind == "mdev" else n // 3  # at least one term
    if ms_arr.size == 0 or ms_arr.min() < 1 or ms_arr.max() > top:
        raise ValueError(f"{kind} cluster sizes must lie in 1..{top} for {n} samples")
    finite = np.isfinite(y)
    gaps = not bool(finite.all())
    if gaps:
        if not finite.any():
            raise ValueError("y has no finite sample")
        ref = float(np.mean(y[finite]))
    else:
        ref = float(np.mean(y))
    S, G = _phase(y, ref, gaps)
    sums = np.zeros(ms_arr.size)
    counts = np.zeros(ms_arr.size, np.int64)
    (_mdev_sums if kind == "mdev" else _ohdev_sums)(S, G, ms_arr, gaps, sums, counts)
    m = ms_arr.astype(np.float64)
    norm = 2.0 * m**4 if kind == "mdev" else 6.0 * m**2
    count = counts.astype(np.float64)
    with np.errstate(invalid="ignore", divide="ignore"):
        var = sums / (norm * count)
    return var, count
