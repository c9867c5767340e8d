r"""JAX kernels of the Allan family on rate data, by cumulative sums (O(n) per tau).

Phase :math:`S_k = \sum_{j<k}(y_j - \bar y)`, block sums :math:`A_i = S_{i+m} - S_i`:
:math:`\sigma^2_{OA} = \sum (A_{i+m} - A_i)^2 / (2m^2L)`, ``L = n+1-2m``;
:math:`H\sigma^2_O = \sum (A_{i+2m} - 2A_{i+m} + A_i)^2 / (6m^2L)`, ``L = n+1-3m``;
:math:`\mathrm{Mod}\,\sigma^2 = \sum_j (\sum_{i=j}^{j+m-1} (A_{i+m} - A_i))^2 / (2m^4L)`, ``L = n+2-3m``
(NIST SP 1065 eqs. 11, 14, 18); non-overlapping variants keep ``i = 0, m, 2m, ...``. Units of ``y``
squared. NaN gaps are counted in a second prefix sum and every term touching one is excluded.
Paths ``direct`` (GPU), ``chunked`` (CPU) and ``mapped`` (thousands of taus) give the same sums.
"""

from __future__ import annotations

from functools import partial

import jax
import jax.numpy as jnp
import numpy as np
from jax import lax

from ..support.programs import program

from .allan_stencils import KINDS, STENCILS, static_counts  # noqa: F401 -- re-exported

_CACHE_WORDS = 1 << 20  # float64 words read per chunk iteration (8 MB: about L2 + L3 share)
_MAX_UNROLLED = 256  # more taus than this: lax.map instead of one unrolled expression


def phase_sums(y: jax.Array, gaps: bool) -> tuple[jax.Array, jax.Array | None]:
    """Mean-removed phase ``S`` (length n+1) and, with ``gaps``, the NaN prefix count ``G``."""
    if not gaps:
        s = jnp.cumsum(y - jnp.mean(y))
        return jnp.concatenate([jnp.zeros(1, s.dtype), s]), None
    ok = jnp.isfinite(y)
    s = jnp.cumsum(jnp.where(ok, y - jnp.nanmean(y), 0.0))
    g = jnp.cumsum(~ok, dtype=jnp.int32)
    zero = jnp.zeros(1, jnp.int32)
    return jnp.concatenate([jnp.zeros(1, s.dtype), s]), jnp.concatenate([zero, g])


def _term(parts: list[jax.Array]) -> jax.Array:
    """Binomial difference of K block sums: A1 - A0 (K=2) or A2 - 2A1 + A0 (K=3)."""
    while len(parts) > 1:
        parts = [b - a for a, b in zip(parts[:-1], parts[1:])]
    return parts[0]


# -- the three code paths for the stencil estimators -----------------------------------
def _direct(S, G, ms, kind):
    k, _, overlap = STENCILS[kind]
    n_phase = S.shape[0]
    sums, counts = [], []
    for m in ms:
        length = n_phase - k * m
        step = 1 if overlap else m
        a = [S[(j + 1) * m:(j + 1) * m + length:step] - S[j * m:j * m + length:step]
             for j in range(k)]
        v = _term(a)
        if G is None:
            sums.append(jnp.sum(v * v))
            counts.append(jnp.asarray(v.shape[0], S.dtype))
        else:
            ok = G[k * m:k * m + length:step] == G[0:length:step]
            sums.append(jnp.sum(jnp.where(ok, v * v, 0.0)))
            counts.append(jnp.sum(ok).astype(S.dtype))
    return jnp.stack(sums), jnp.stack(counts)


def _chunk_size(ms, k) -> int:
    """Samples per chunk: the slices of one iteration (one per distinct offset) fill about
    ``_CACHE_WORDS`` words, between 1024 and 65536 samples."""
    offsets = len({j * m for m in ms for j in range(k + 1)})
    return int(2 ** np.clip(np.floor(np.log2(_CACHE_WORDS / offsets)), 10, 16))


def _chunked(S, G, ms, kind):
    k, _, _ = STENCILS[kind]  # overlapping kinds only
    chunk = _chunk_size(ms, k)
    n_phase = S.shape[0]
    n_chunks = -(-n_phase // chunk)
    pad = n_chunks * chunk + k * max(ms) - n_phase
    Sp = jnp.pad(S, (0, pad))
    Gp = None if G is None else jnp.pad(G, (0, pad), constant_values=-1)
    limits = jnp.array([n_phase - k * m for m in ms])

    def body(c, acc):
        i0 = c * chunk
        idx = i0 + jnp.arange(chunk)
        cache = {}

        def at(arr, off):  # CSE by hand: octave grids share offsets (2m of one tau = m of next)
            if (id(arr), off) not in cache:
                cache[id(arr), off] = lax.dynamic_slice(arr, (i0 + off,), (chunk,))
            return cache[id(arr), off]

        out_s, out_c = [], []
        for t, m in enumerate(ms):
            v = _term([at(Sp, (j + 1) * m) - at(Sp, j * m) for j in range(k)])
            ok = idx < limits[t]
            if Gp is not None:
                ok = ok & (at(Gp, k * m) == at(Gp, 0))
            out_s.append(jnp.sum(jnp.where(ok, v * v, 0.0)))
            out_c.append(jnp.sum(ok))
        return acc[0] + jnp.stack(out_s), acc[1] + jnp.stack(out_c)

    init = (jnp.zeros(len(ms), S.dtype), jnp.zeros(len(ms), jnp.int64))
    sums, counts = lax.fori_loop(0, n_chunks, body, init)
    return sums, counts.astype(S.dtype)


def _mapped(S, G, ms, kind):
    k, _, overlap = STENCILS[kind]
    n_phase = S.shape[0]
    pad = k * max(ms)
    Sp = jnp.pad(S, (0, pad))
    Gp = None if G is None else jnp.pad(G, (0, pad), constant_values=-1)
    idx = jnp.arange(n_phase)

    def one(m):
        a = [lax.dynamic_slice(Sp, ((j + 1) * m,), (n_phase,))
             - lax.dynamic_slice(Sp, (j * m,), (n_phase,)) for j in range(k)]
        v = _term(a)
        ok = idx < n_phase - k * m
        if not overlap:
            ok = ok & (idx % m == 0)
        if Gp is not None:
            ok = ok & (lax.dynamic_slice(Gp, (k * m,), (n_phase,)) == Gp[:n_phase])
        return jnp.sum(jnp.where(ok, v * v, 0.0)), jnp.sum(ok).astype(S.dtype)

    return lax.map(one, jnp.asarray(ms))


def _modified(S, G, ms):
    """Modified Allan: inner sums of m consecutive Allan terms via a per-tau prefix sum.

    The inner sums come from the prefix sum of the (small, zero-mean) Allan terms rather
    than from a double prefix sum of the phase, which would grow like n^1.5 and cancel.
    """
    n_phase = S.shape[0]
    sums, counts = [], []
    for m in ms:
        length = n_phase - 2 * m
        d = (S[2 * m:] - S[m:m + length]) - (S[m:m + length] - S[:length])
        D = jnp.concatenate([jnp.zeros(1, S.dtype), jnp.cumsum(d)])
        inner = D[m:] - D[:-m]  # length n_phase - 3m + 1
        if G is None:
            sums.append(jnp.sum(inner * inner))
            counts.append(jnp.asarray(inner.shape[0], S.dtype))
        else:
            span = 3 * m - 1  # samples y_j .. y_{j+3m-2}
            ok = G[span:span + inner.shape[0]] == G[:inner.shape[0]]
            sums.append(jnp.sum(jnp.where(ok, inner * inner, 0.0)))
            counts.append(jnp.sum(ok).astype(S.dtype))
    return jnp.stack(sums), jnp.stack(counts)


def _modified_mapped(S, G, ms):
    """:func:`_modified` for many taus: ``lax.map`` over m with padded dynamic slices."""
    n_phase = S.shape[0]
    pad = 3 * max(ms)
    Sp = jnp.pad(S, (0, pad))
    Gp = None if G is None else jnp.pad(G, (0, pad), constant_values=-1)
    idx = jnp.arange(n_phase)

    def one(m):
        s1 = lax.dynamic_slice(Sp, (m,), (n_phase,))
        s2 = lax.dynamic_slice(Sp, (2 * m,), (n_phase,))
        d = jnp.where(idx < n_phase - 2 * m, (s2 - s1) - (s1 - S), 0.0)
        D = jnp.pad(jnp.concatenate([jnp.zeros(1, S.dtype), jnp.cumsum(d)]), (0, pad))
        inner = lax.dynamic_slice(D, (m,), (n_phase,)) - D[:n_phase]
        ok = idx < n_phase - 3 * m + 1
        if Gp is not None:
            ok = ok & (lax.dynamic_slice(Gp, (3 * m - 1,), (n_phase,)) == Gp[:n_phase])
        return jnp.sum(jnp.where(ok, inner * inner, 0.0)), jnp.sum(ok).astype(S.dtype)

    return lax.map(one, jnp.asarray(ms))


def _choose(kind: str, ms: tuple[int, ...], method: str) -> str:
    if kind == "mdev":
        return "modified_mapped" if len(ms) > _MAX_UNROLLED or method == "mapped" else "modified"
    if method != "auto":
        return method
    if len(ms) > _MAX_UNROLLED:
        return "mapped"
    overlap = STENCILS[kind][2]
    return "chunked" if overlap and jax.default_backend() == "cpu" else "direct"


@partial(program, static_argnames=("ms", "kind", "gaps", "method"))
def allan_sums(y: jax.Array, ms: tuple[int, ...], kind: str = "oadev", gaps: bool = False,
               method: str = "auto") -> tuple[jax.Array, jax.Array]:
    """Sums of squared terms and term counts, one per cluster size in ``ms``.

    Args:
        y: rate samples, shape (n,), float64; NaN marks missing samples when ``gaps``.
        ms: cluster sizes (static tuple of ints, each with at least one term).
        kind: ``oadev``, ``adev``, ``ohdev``, ``hdev`` or ``mdev``.
        gaps: True when ``y`` may contain NaN (slower: a second prefix sum and masks).
        method: ``auto``, ``direct``, ``chunked`` (overlapping kinds) or ``mapped``.

    Returns:
        ``(sums, counts)``, each shape (len(ms),). The variance is
        ``sums / (norm * m**2 * counts)`` (``norm`` 2 Allan, 6 Hadamard; ``2 m**4`` for mdev).
    """
    S, G = phase_sums(y, gaps)
    how = _choose(kind, ms, method)
    if how == "modified":
        return _modified(S, G, ms)
    if how == "modified_mapped":
        return _modified_mapped(S, G, ms)
    return {"direct": _direct, "chunked": _chunked, "mapped": _mapped}[how](S, G, ms, kind)


@partial(program, static_argnames=("ms", "kind", "gaps", "method"))
def allan_variance(y: jax.Array, ms: tuple[int, ...], kind: str = "oadev", gaps: bool = False,
                   method: str = "auto") -> tuple[jax.Array, jax.Array]:
    """Variance of the named kind and the number of terms used, per cluster size.

    ``y`` may be (n,) or (batch, n); a batch is mapped with ``vmap`` on accelerators and with
    ``lax.map`` on CPU (one compilation either way).

    Example:
        >>> import numpy as np
        >>> y = np.random.default_rng(0).normal(size=4096)
        >>> var, count = allan_variance(y, (1, 2, 4))
        >>> bool(abs(var[0] - 1.0) < 0.1), int(count[0])
        (True, 4096)
    """
    y = jnp.asarray(y)
    fn = partial(allan_sums, ms=ms, kind=kind, gaps=gaps, method=method)
    if y.ndim == 1:
        sums, counts = fn(y)
    elif jax.default_backend() == "cpu":
        # one sensor after the other: the chunked CPU kernel keeps its slices in cache, which
        # a vmapped (batched gather) version does not; same numbers, ~2x faster here
        sums, counts = lax.map(fn, y)
    else:
        sums, counts = jax.vmap(fn)(y)
    m = jnp.asarray(ms, dtype=sums.dtype)
    norm = 2.0 * m**4 if kind == "mdev" else STENCILS[kind][1] * m**2
    return sums / (norm * counts), counts
