"""Fused compiled loops behind the Allan accumulators (Numba, CPU, ``nogil``, ``cache=True``).

Per chunk and level or tau (equations of :mod:`fogbayes.stats.allan_accumulators`): pyramid
:math:`D_m(j) = B_m(j) - B_m(j-m)`, :math:`B_{2m}(j) = B_m(j) + B_m(j-m)`; phase window
:math:`D_m(e) = (S_e + S_{e-2m}) - 2S_{e-m}`. Squares are summed in pieces of :data:`PIECE`
terms, added with Neumaier compensation into ``sums``/``comps``; NaN terms are skipped and counted.
"""

from __future__ import annotations

from ..support.numba_cache import numba
import numpy as np

PIECE = 8192  # terms per compensated addition

_FAST = {"reassoc", "contract"}  # SIMD reductions; NaN and inf semantics are kept


@numba.njit(cache=True, inline="always")
def _add(sums, comps, k, x):
    """Neumaier-compensated ``sums[k] += x``."""
    s = sums[k]
    t = s + x
    if abs(s) >= abs(x):
        comps[k] += (s - t) + x
    else:
        comps[k] += (x - t) + s
    sums[k] = t


# The loops index slices, not ``store[offset + i]``: Numba wraps negative indices, and that
# check on a computed index kept LLVM from vectorising (0.62 ns per term against 0.12).

@numba.njit(cache=True, fastmath=_FAST)
def _sumsq_diff(new, old):
    acc = 0.0
    for i in range(new.shape[0]):
        d = new[i] - old[i]
        acc += d * d
    return acc


@numba.njit(cache=True, fastmath=_FAST)
def _sumsq_diff_and_add(new, old, out):
    """Sum of (new - old)^2 while writing new + old into ``out`` (one pass)."""
    acc = 0.0
    for i in range(new.shape[0]):
        a = new[i]
        b = old[i]
        d = a - b
        acc += d * d
        out[i] = a + b
    return acc


@numba.njit(cache=True)
def _sumsq_diff_nan(new, old):
    acc = 0.0
    bad = 0
    for i in range(new.shape[0]):
        d = new[i] - old[i]
        if d != d:
            bad += 1
        else:
            acc += d * d
    return acc, bad


@numba.njit(cache=True, fastmath=_FAST)
def _add_into(new, old, out):
    for i in range(new.shape[0]):
        out[i] = new[i] + old[i]


@numba.njit(cache=True, nogil=True)
def octave_step(y, offset, store, base, size, ring, ms, j0, sums, comps, nans):
    """Push ``w = len(y)`` samples (ending at a chunk boundary) through every pyramid level.

    ``store`` holds every level's buffer: level ``k`` occupies
    ``store[base[k]:base[k] + size[k]]`` with ``size[k] = ms[k] + chunk``. Levels with
    ``ring[k]`` are rings whose slots are aligned to the chunk; the others keep the last
    ``ms[k]`` block sums at the front and take new ones after them.
    """
    w = y.shape[0]
    K = ms.shape[0]
    if ring[0]:
        d0 = base[0] + j0 % size[0]
    else:
        d0 = base[0] + ms[0]
    first = store[d0:d0 + w]
    for i in range(w):
        first[i] = y[i] - offset
    for k in range(K):
        m = ms[k]
        if ring[k]:
            p = j0 % size[k]
            pn = base[k] + p
            po = base[k] + (p - m) % size[k]
        else:
            pn = base[k] + m
            po = base[k]
        lo = min(max(0, 2 * m - 1 - j0), w)  # D_m(j) exists from j = 2m - 1 on
        last = k + 1 == K
        if not last:
            if ring[k + 1]:
                dst = base[k + 1] + j0 % size[k + 1]
            else:
                dst = base[k + 1] + ms[k + 1]
            if lo > 0:
                _add_into(store[pn:pn + lo], store[po:po + lo], store[dst:dst + lo])
        for a in range(lo, w, PIECE):
            b = min(a + PIECE, w)
            new = store[pn + a:pn + b]
            old = store[po + a:po + b]
            if last:
                s = _sumsq_diff(new, old)
            else:
                s = _sumsq_diff_and_add(new, old, store[dst + a:dst + b])
            if s != s:
                s, bad = _sumsq_diff_nan(new, old)
                nans[k] += bad
            _add(sums, comps, k, s)
        if not ring[k]:
            keep = store[base[k]:base[k] + m]
            src = store[base[k] + w:base[k] + w + m]
            for i in range(m):  # keep the last m block sums (source ahead: forward copy)
                keep[i] = src[i]


@numba.njit(cache=True, nogil=True)
def octave_feed(y, offset, store, base, size, ring, ms, n0, chunk, sums, comps, nans):
    """:func:`octave_step` over all of ``y`` in steps that end on multiples of ``chunk``
    (ring slots never wrap); returns the new sample count. One call, so the GIL stays
    released for the whole record (a thread beside it runs Python code meanwhile)."""
    a = 0
    n = n0
    while a < y.shape[0]:
        w = min(y.shape[0] - a, chunk - n % chunk)
        octave_step(y[a:a + w], offset, store, base, size, ring, ms, n, sums, comps, nans)
        n += w
        a += w
    return n


@numba.njit(cache=True, fastmath=_FAST)
def _sumsq_phase(end, start, mid2):
    acc = 0.0
    for i in range(end.shape[0]):
        t = (end[i] + start[i]) - mid2[i]
        acc += t * t
    return acc


@numba.njit(cache=True)
def _sumsq_phase_gaps(end, start, mid2, g_end, g_start):
    acc = 0.0
    kept = 0
    for i in range(end.shape[0]):
        if g_end[i] == g_start[i]:
            t = (end[i] + start[i]) - mid2[i]
            acc += t * t
            kept += 1
    return acc, kept


@numba.njit(cache=True, nogil=True)
def phase_step(P, P2, G, has_gaps, first, lo_slot, hi_slot, ms, sums, comps, kept):
    """Add the terms ending at window slots ``lo_slot .. hi_slot - 1`` for every tau.

    Slot ``s`` holds phase index ``s + first``; a term at ``m`` ends at phase index >= 2m,
    and the window keeps at least ``2 max(m)`` slots before ``lo_slot``.
    ``G`` (used when ``has_gaps``) counts NaN samples up to each slot: a term is kept when
    no sample between its ends is NaN.
    """
    for k in range(ms.shape[0]):
        m = ms[k]
        start = max(lo_slot, 2 * m - first)  # first slot whose term exists
        stop = hi_slot
        if start >= stop:
            continue
        for a in range(start, stop, PIECE):
            b = min(a + PIECE, stop)
            e, s0, mid2 = P[a:b], P[a - 2 * m:b - 2 * m], P2[a - m:b - m]
            if has_gaps and G[b - 1] != G[a - 2 * m]:
                s, c = _sumsq_phase_gaps(e, s0, mid2, G[a:b], G[a - 2 * m:b - 2 * m])
                kept[k] += c
            else:
                s = _sumsq_phase(e, s0, mid2)
                kept[k] += b - a
            _add(sums, comps, k, s)


def empty_gaps() -> np.ndarray:
    """A placeholder NaN-count array for windows without gaps."""
    return np.zeros(1, np.int64)
