"""In-memory overlapping Allan variance by the streaming accumulators (compiled, cache-blocked).

The estimator of :func:`fogbayes.stats.allan_kernels.allan_variance` with ``kind="oadev"``
(NIST SP 1065 eq. 11; :mod:`fogbayes.stats.allan_accumulators`), in one pass over the record
in cache-sized chunks; batches run one sensor per thread. Returns variances and term counts
only (no noise identification or intervals); NaN gaps as ``allan_variance``. Why not XLA on
CPU: benchmarks/RESULTS_allan.md.
"""

from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor

import numpy as np

from ..errors import FogbayesError, TooShortError
from .taus import cluster_sizes
from .allan_accumulators import (DEFAULT_CHUNK, OCTAVE_CHUNK, OctaveAccumulator,
                                 PhaseAccumulator, variance)


def is_octave(ms) -> bool:
    """True when every cluster size is a power of two (the pyramid applies)."""
    ms = np.asarray(ms, dtype=np.int64)
    return bool(ms.size and np.all(ms > 0) and np.all((ms & (ms - 1)) == 0))


def accumulator(ms, *, chunk: int | None = None):
    """The accumulator for ``ms`` and a function mapping its result onto ``ms``.

    ``chunk``: samples per step (default: :data:`OCTAVE_CHUNK` for the pyramid,
    :data:`DEFAULT_CHUNK` for the phase window)."""
    ms = tuple(int(m) for m in np.unique(np.asarray(ms, dtype=np.int64)))
    if is_octave(ms):
        acc = OctaveAccumulator(int(np.log2(ms[-1])) + 1, chunk=chunk or OCTAVE_CHUNK)
        idx = np.log2(np.asarray(ms)).astype(int)
        return acc, ms, lambda s, c: (s[idx], c[idx])
    return PhaseAccumulator(ms, chunk=chunk or DEFAULT_CHUNK), ms, lambda s, c: (s, c)


def allan_variance_fast(y, ms, *, chunk: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Overlapping AVAR and terms kept at cluster sizes ``ms`` of rate samples ``y``.

    ``y``: (n,) or (batch, n); NaN marks missing samples (every term touching one is
    excluded), +-inf is an error. ``ms`` are sorted and de-duplicated; each needs 2m <= n.
    Matches ``allan_variance(y, ms, kind="oadev")`` to rounding (about 1e-12 relative).
    """
    y = np.asarray(y, dtype=float)
    if y.ndim == 2:  # sensors on threads: the compiled steps release the GIL
        workers = max(1, min(len(y), os.cpu_count() or 1))
        with ThreadPoolExecutor(workers) as pool:
            parts = list(pool.map(lambda row: allan_variance_fast(row, ms, chunk=chunk), y))
        return np.stack([p[0] for p in parts]), np.stack([p[1] for p in parts])
    if y.ndim != 1:
        raise FogbayesError(f"rate data must be 1-D (or 2-D for a batch), got shape {y.shape}",
                            fix="pass one sensor as (n,) or a batch as (sensors, n)")
    acc, ms, pick = accumulator(ms, chunk=chunk)
    if 2 * ms[-1] > y.size or ms[0] < 1:
        raise TooShortError(f"cluster sizes must lie in 1..{y.size // 2} for {y.size} samples",
                            argument="taus", fix="pass smaller cluster sizes (samples, not s)")
    acc.update(y)
    sums, counts = pick(*acc.result())
    return variance(ms, sums, counts), counts


def oadev_fast(y, fs: float, *, taus="octave", per_decade: int = 20, m_max: int | None = None,
               chunk: int | None = None):
    """(tau s, overlapping ADEV, terms kept) on a named grid or explicit cluster sizes."""
    y = np.asarray(y, dtype=float)
    n = y.shape[-1]
    ms = (cluster_sizes(n, taus, per_decade=per_decade, m_max=m_max, kind="oadev")
          if isinstance(taus, str) else tuple(np.unique(np.asarray(taus, dtype=np.int64))))
    var, count = allan_variance_fast(y, ms, chunk=chunk)
    return np.asarray(ms) / float(fs), np.sqrt(var), count
