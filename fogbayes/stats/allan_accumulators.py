r"""Overlapping Allan variance accumulated chunk by chunk in O(max lag + chunk) memory.

With block sums :math:`B_m(j) = \sum_{k=j-m+1}^{j} y_k` and :math:`D_m(j) = B_m(j) - B_m(j-m)`,
:math:`\sigma^2(m) = \sum_j D_m(j)^2 / (2 m^2 L)`, ``L = n - 2m + 1`` (NIST SP 1065 eq. 11).
:class:`OctaveAccumulator` (m = 2^k) uses the Haar pyramid :math:`B_{2m}(j) = B_m(j) + B_m(j-m)`;
:class:`PhaseAccumulator` (any m) a compacted window of the phase. Sums of squares are added
in pieces with Neumaier compensation; terms spanning a NaN are dropped (``counts`` = kept).
The per-chunk loops are :mod:`fogbayes.stats.allan_loops`.
"""

from __future__ import annotations

import numpy as np

from ..errors import FogbayesError
from .allan_loops import empty_gaps, octave_feed, phase_step

_NO_GAPS = empty_gaps()

DEFAULT_CHUNK = 1 << 16  # samples per internal step: a few arrays of 512 KB stay in L2/L3
#: The pyramid's step: each level reads two and writes one array of the step per step, so
#: 64 KB arrays stay in L2 (measured 2026-11-25: 1 << 13 is 12 % faster than 1 << 16 on 2^20
#: samples and 25 % on 1e7; the phase window keeps DEFAULT_CHUNK, since it moves its
#: 2 max(m) history once per step).
OCTAVE_CHUNK = 1 << 13


def _offset(y: np.ndarray) -> float:
    """A provisional level to subtract: the mean of the finite samples (0 if none)."""
    ok = np.isfinite(y)
    return float(y[ok].mean()) if ok.any() else 0.0


def _check_inf(y: np.ndarray, start: int) -> None:
    if np.isfinite(np.add.reduce(y)):  # one SIMD pass: no inf (and no NaN) anywhere
        return
    bad = np.flatnonzero(np.isinf(y))
    if bad.size:
        raise FogbayesError(f"rate data contain +-inf (first at sample {start + int(bad[0])})",
                            row=start + int(bad[0]), fix="mark missing samples as NaN")


class OctaveAccumulator:
    """Overlapping AVAR sums at m = 1, 2, ..., 2^(levels-1), fed chunk by chunk."""

    def __init__(self, levels: int, *, chunk: int = OCTAVE_CHUNK):
        if levels < 1:
            raise FogbayesError("need at least one octave level", fix="pass levels >= 1")
        self.ms = tuple(1 << k for k in range(levels))
        self.chunk = int(chunk)
        c = self.chunk
        if any(m >= c and m % c for m in self.ms):
            raise FogbayesError(f"chunk {c} must be a power of two", fix="pass e.g. chunk=8192")
        # level k: [last m block sums | new chunk] when m < chunk; when m >= chunk a ring of
        # m + chunk values whose slots are aligned to the chunk, so old and new never wrap
        # or overlap. All levels live in one array for the compiled step.
        self._ms = np.asarray(self.ms, np.int64)
        self._size = self._ms + c
        self._base = np.concatenate([[0], np.cumsum(self._size)[:-1]]).astype(np.int64)
        self._ring = np.asarray([m >= c for m in self.ms])
        self._store = np.zeros(int(self._size.sum()))
        self._sums = np.zeros(levels)
        self._comps = np.zeros(levels)
        self._nan = np.zeros(levels, np.int64)
        self.offset: float | None = None
        self.n = 0

    @property
    def nbytes(self) -> int:
        return self._store.nbytes

    def update(self, y: np.ndarray) -> None:
        """Add the next samples (any length)."""
        y = np.ascontiguousarray(y, dtype=float)
        if self.offset is None and y.size:
            self.offset = _offset(y[:self.chunk])
        _check_inf(y, self.n)
        # steps end on multiples of the chunk (ring slots never wrap), all in one call
        self.n = int(octave_feed(y, self.offset, self._store, self._base, self._size,
                                 self._ring, self._ms, self.n, self.chunk, self._sums,
                                 self._comps, self._nan))

    def result(self) -> tuple[np.ndarray, np.ndarray]:
        """(sums of squared terms, terms kept) per level; levels without terms get count 0."""
        full = np.maximum(self.n - 2 * self._ms + 1, 0)
        return self._sums + self._comps, (full - self._nan).astype(float)


class PhaseAccumulator:
    """Overlapping AVAR sums at any cluster sizes ``ms``, fed chunk by chunk."""

    def __init__(self, ms, *, chunk: int = DEFAULT_CHUNK):
        ms = np.unique(np.asarray(ms, dtype=np.int64))
        if ms.size == 0 or ms[0] < 1:
            raise FogbayesError("cluster sizes must be positive integers", argument="taus",
                                fix="pass cluster sizes m >= 1 (samples)")
        self.ms = tuple(int(m) for m in ms)
        self._ms = ms
        self.chunk = int(chunk)
        self.keep = 2 * self.ms[-1]  # phase points a term looks back
        # window: kept history + room for several chunks, so compaction (a copy of `keep`
        # values) happens at most once per `keep` new samples
        self._cap = self.keep + max(self.keep, self.chunk) + self.chunk
        self._P = np.zeros(self._cap)
        self._P2 = np.zeros(self._cap)
        self._G: np.ndarray | None = None  # NaN counts, created at the first NaN
        self._end = 1  # window holds phase points [n + 1 - _end, n]; S_0 = 0 is at slot 0
        self._sums = np.zeros(len(self.ms))
        self._comps = np.zeros(len(self.ms))
        self._kept = np.zeros(len(self.ms), np.int64)
        self.offset: float | None = None
        self.n = 0

    @property
    def nbytes(self) -> int:
        g = 0 if self._G is None else self._G.nbytes
        return self._P.nbytes + self._P2.nbytes + g

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
        gaps = self._G is not None
        phase_step(self._P, self._P2, self._G if gaps else _NO_GAPS, gaps, self.n + 1 - e0,
                   e0, self._end, self._ms, self._sums, self._comps, self._kept)
        self.n += w

    def result(self) -> tuple[np.ndarray, np.ndarray]:
        return self._sums + self._comps, self._kept.astype(float)


def variance(ms, sums: np.ndarray, counts: np.ndarray) -> np.ndarray:
    """AVAR sums / (2 m^2 count); NaN where no term was kept."""
    m = np.asarray(ms, dtype=float)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(counts > 0, sums / (2.0 * m * m * counts), np.nan)
