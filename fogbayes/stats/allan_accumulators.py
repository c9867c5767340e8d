r"""Overlapping Allan variance accumulated chunk by chunk in O(max lag + chunk) memory.

With rate samples :math:`y_j`, the block sum of ``m`` samples ending at ``j`` and the
overlapping Allan term completed at ``j`` are

.. math::

    B_m(j) = \sum_{k=j-m+1}^{j} y_k, \qquad D_m(j) = B_m(j) - B_m(j-m),
    \qquad \sigma^2(m) = \frac{1}{2 m^2 L} \sum_{j=2m-1}^{n-1} D_m(j)^2, \quad L = n-2m+1,

which is NIST SP 1065 eq. 11 (with phase :math:`x = S/f_s`, :math:`S_k = \sum_{j<k} y_j`,
:math:`D_m(j) = S_{j+1} - 2 S_{j+1-m} + S_{j+1-2m}`) and the estimator of
:mod:`fogbayes.stats.allan_kernels`. Two accumulators compute it while the samples stream
past, each keeping only what the largest lag needs:

* :class:`OctaveAccumulator` (m = 1, 2, 4, ..., 2^(K-1)): the Haar pyramid
  :math:`B_{2m}(j) = B_m(j) + B_m(j-m)`, :math:`D_m(j) = B_m(j) - B_m(j-m)`: two additions
  and a sum of squares per sample and level, and a buffer of the last ``m`` block sums per
  level (about ``2 * 2^(K-1) + K * chunk`` floats in all). No phase is ever formed: each
  :math:`B_m` is a sum of ``m`` samples by a binary tree, so rounding stays relative to the
  block sums themselves, never to a phase that wanders over the whole record.
* :class:`PhaseAccumulator` (any set of m): a window of the last ``2 max(m) + chunk`` phase
  points, :math:`D = (S_e + S_{e-2m}) - 2 S_{e-m}` per tau (``2 S`` kept alongside: doubling
  is exact). The window is compacted (its tail moved to the front and re-based to 0) when
  full, so the phase stays the local excursion over about ``4 max(m)`` samples.

Both subtract a provisional offset (the first chunk's mean; the variance does not depend on
a constant offset) and accumulate each level's sum of squares in pieces of 8192 terms
(``numpy.dot``, kept below OpenBLAS's threading threshold, which on a busy 2-core machine
made it 20x slower) combined by Neumaier-compensated addition, so a 2e9-sample sum loses no
more than a few units in the last place.

Gaps: NaN samples are missing. A term is kept only if none of its ``2m`` samples is NaN (as
:mod:`fogbayes.stats.allan_kernels` does); ``counts`` are the terms kept. The pyramid lets
NaN propagate (a NaN block sum poisons exactly the terms that span it) and only inspects a
piece whose sum came out NaN; the phase accumulator keeps a running NaN count.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import FogbayesError

PIECE = 8192  # terms per numpy.dot: single-threaded in OpenBLAS (threshold 10 000)
DEFAULT_CHUNK = 1 << 16  # samples per internal step: a few arrays of 512 KB stay in L2/L3


class _Compensated:
    """Neumaier-compensated running sums, one per level."""

    def __init__(self, k: int):
        self.s = [0.0] * k
        self.c = [0.0] * k

    def add(self, i: int, x: float) -> None:
        s = self.s[i]
        t = s + x
        self.c[i] += (s - t) + x if abs(s) >= abs(x) else (x - t) + s
        self.s[i] = t

    def total(self) -> np.ndarray:
        return np.array([s + c for s, c in zip(self.s, self.c)])


_VECDOT = getattr(np, "vecdot", None)  # NumPy >= 2: one call for all pieces


def _sumsq(d: np.ndarray) -> tuple[float, int]:
    """Sum of squares of the finite entries of ``d`` and how many are NaN."""
    full = d.size - d.size % PIECE
    if _VECDOT is not None and full:
        rows = d[:full].reshape(-1, PIECE)
        s = float(_VECDOT(rows, rows).sum())
    else:
        full, s = 0, 0.0
    for a in range(full, d.size, PIECE):
        p = d[a:a + PIECE]
        s += float(np.dot(p, p))
    if not math.isnan(s):  # the usual case costs nothing more
        return s, 0
    bad = np.isnan(d)
    g = d[~bad]
    return float(np.dot(g, g)), int(bad.sum())


def _offset(y: np.ndarray) -> float:
    """A provisional level to subtract: the mean of the finite samples (0 if none)."""
    ok = np.isfinite(y)
    return float(y[ok].mean()) if ok.any() else 0.0


def _check_inf(y: np.ndarray, start: int) -> None:
    bad = np.flatnonzero(np.isinf(y))
    if bad.size:
        raise FogbayesError(f"rate data contain +-inf (first at sample {start + int(bad[0])})",
                            row=start + int(bad[0]), fix="mark missing samples as NaN")


class OctaveAccumulator:
    """Overlapping AVAR sums at m = 1, 2, ..., 2^(levels-1), fed chunk by chunk."""

    def __init__(self, levels: int, *, chunk: int = DEFAULT_CHUNK):
        if levels < 1:
            raise FogbayesError("need at least one octave level", fix="pass levels >= 1")
        self.ms = tuple(1 << k for k in range(levels))
        self.chunk = int(chunk)
        c = self.chunk
        # m < chunk: [last m block sums | new chunk]; m >= chunk: a ring of m + chunk values
        # whose slots are aligned to the chunk, so old and new never wrap or overlap.
        self._buf = [np.zeros(m + c) for m in self.ms]
        self._ring = [m >= c and m % c == 0 for m in self.ms]
        if any(m >= c and m % c for m in self.ms):
            raise FogbayesError(f"chunk {c} must be a power of two", fix="pass chunk=65536")
        self._d = np.empty(c)
        self._sums = _Compensated(levels)
        self._nan = np.zeros(levels, np.int64)
        self.offset: float | None = None
        self.n = 0

    @property
    def nbytes(self) -> int:
        return sum(b.nbytes for b in self._buf) + self._d.nbytes

    def update(self, y: np.ndarray) -> None:
        """Add the next samples (any length)."""
        y = np.asarray(y, dtype=float)
        if self.offset is None and y.size:
            self.offset = _offset(y[:self.chunk])
        _check_inf(y, self.n)
        a = 0
        while a < y.size:  # steps end on multiples of the chunk: ring slots never wrap
            w = min(y.size - a, self.chunk - self.n % self.chunk)
            self._step(y[a:a + w])
            a += w

    def _new_slot(self, k: int, w: int) -> np.ndarray:
        m, buf = self.ms[k], self._buf[k]
        if not self._ring[k]:
            return buf[m:m + w]
        p = self.n % buf.size
        return buf[p:p + w]

    def _step(self, y: np.ndarray) -> None:
        w, j0, K = y.size, self.n, len(self.ms)
        np.subtract(y, self.offset, out=self._new_slot(0, w))
        for k, m in enumerate(self.ms):
            buf = self._buf[k]
            if self._ring[k]:
                p = j0 % buf.size
                new, po = buf[p:p + w], (p - m) % buf.size
                old = buf[po:po + w]
            else:
                old, new = buf[0:w], buf[m:m + w]
            lo = max(0, 2 * m - 1 - j0)  # D_m(j) exists from j = 2m - 1 on
            if lo < w:
                d = self._d[:w - lo]
                np.subtract(new[lo:], old[lo:], out=d)
                s, bad = _sumsq(d)
                self._sums.add(k, s)
                self._nan[k] += bad
            if k + 1 < K:
                np.add(new, old, out=self._new_slot(k + 1, w))
            if not self._ring[k]:
                buf[0:m] = buf[w:w + m]  # keep the last m block sums
        self.n += w

    def result(self) -> tuple[np.ndarray, np.ndarray]:
        """(sums of squared terms, terms kept) per level; levels without terms get count 0."""
        ms = np.asarray(self.ms)
        full = np.maximum(self.n - 2 * ms + 1, 0)
        return self._sums.total(), (full - self._nan).astype(float)


class PhaseAccumulator:
    """Overlapping AVAR sums at any cluster sizes ``ms``, fed chunk by chunk."""

    def __init__(self, ms, *, chunk: int = DEFAULT_CHUNK):
        ms = np.unique(np.asarray(ms, dtype=np.int64))
        if ms.size == 0 or ms[0] < 1:
            raise FogbayesError("cluster sizes must be positive integers", column="taus",
                                fix="pass cluster sizes m >= 1 (samples)")
        self.ms = tuple(int(m) for m in ms)
        self.chunk = int(chunk)
        self.keep = 2 * self.ms[-1]  # phase points a term looks back
        # window: kept history + room for several chunks, so compaction (a copy of `keep`
        # values) happens at most once per `keep` new samples
        self._cap = self.keep + max(self.keep, self.chunk) + self.chunk
        self._P = np.zeros(self._cap)
        self._P2 = np.zeros(self._cap)
        self._G: np.ndarray | None = None  # NaN counts, created at the first NaN
        self._t = np.empty(self.chunk)
        self._end = 1  # window holds phase points [n + 1 - _end, n]; S_0 = 0 is at slot 0
        self._sums = _Compensated(len(self.ms))
        self._kept = np.zeros(len(self.ms), np.int64)
        self.offset: float | None = None
        self.n = 0

    @property
    def nbytes(self) -> int:
        g = 0 if self._G is None else self._G.nbytes
        return self._P.nbytes + self._P2.nbytes + self._t.nbytes + g

    def update(self, y: np.ndarray) -> None:
        y = np.asarray(y, dtype=float)
        if self.offset is None and y.size:
            self.offset = _offset(y[:self.chunk])
        _check_inf(y, self.n)
        for a in range(0, y.size, self.chunk):
            self._step(y[a:a + self.chunk])

    def _compact(self) -> None:
        keep = min(self.keep, self._end)
        lo = self._end - keep
        base = self._P[lo]
        self._P[:keep] = self._P[lo:self._end] - base  # re-base: the phase stays local
        np.multiply(self._P[:keep], 2.0, out=self._P2[:keep])
        if self._G is not None:
            self._G[:keep] = self._G[lo:self._end]
        self._end = keep

    def _step(self, y: np.ndarray) -> None:
        w = y.size
        if self._end + w > self._cap:
            self._compact()
        e0 = self._end  # slot of phase point n + 1
        y0 = y - self.offset
        nan = np.isnan(y0)
        if nan.any():
            if self._G is None:
                self._G = np.zeros(self._cap, np.int64)
            y0[nan] = 0.0
        if self._G is not None:
            np.cumsum(nan, out=self._G[e0:e0 + w])
            self._G[e0:e0 + w] += self._G[e0 - 1]
        seg = self._P[e0:e0 + w]
        np.cumsum(y0, out=seg)
        seg += self._P[e0 - 1]
        np.multiply(seg, 2.0, out=self._P2[e0:e0 + w])
        self._end = e0 + w
        first = self.n + 1  # global phase index of slot e0
        for k, m in enumerate(self.ms):
            g_lo = max(first, 2 * m)  # terms end at phase index e >= 2m
            if g_lo > self.n + w:
                continue
            a = e0 + (g_lo - first)  # slot of the first term's end
            cnt = self._end - a
            t = self._t[:cnt]
            np.add(self._P[a:self._end], self._P[a - 2 * m:self._end - 2 * m], out=t)
            np.subtract(t, self._P2[a - m:self._end - m], out=t)
            if self._G is not None and self._G[self._end - 1] != self._G[a - 2 * m]:
                ok = self._G[a:self._end] == self._G[a - 2 * m:self._end - 2 * m]
                t[~ok] = 0.0
                kept = int(ok.sum())
            else:
                kept = cnt
            s, _ = _sumsq(t)
            self._sums.add(k, s)
            self._kept[k] += kept
        self.n += w

    def result(self) -> tuple[np.ndarray, np.ndarray]:
        return self._sums.total(), self._kept.astype(float)


def variance(ms, sums: np.ndarray, counts: np.ndarray) -> np.ndarray:
    """AVAR sums / (2 m^2 count); NaN where no term was kept."""
    m = np.asarray(ms, dtype=float)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(counts > 0, sums / (2.0 * m * m * counts), np.nan)
