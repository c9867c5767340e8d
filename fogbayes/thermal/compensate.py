"""Compensators for bias models, compiled once per model structure.

y_comp[i] = y[i] - X(z_i) @ coef for a :class:`fogbayes.models.polynomial.PolyBasis`.
:func:`bias_compensator`: ``jit(f)`` / ``jit(vmap(f))`` with coefficients, centre and scale as
arguments (on CPU the loop of :mod:`fogbayes.thermal.compensate_loops`); float32 usable since
covariates are scaled first. Composite: :mod:`fogbayes.composite.compensate`.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator
from functools import lru_cache
from typing import NamedTuple

import numpy as np

from ..support.lazy import jax_on_cpu, lazy_module
from .compensate_loops import compensate_into
from ..models.polynomial import PolyBasis
from ..support.programs import program

jax = lazy_module("jax")  # the jitted compensator only: one-off calls take the NumPy path


class Compensator(NamedTuple):
    """``single(coef (p,), z (n, c), y (n,))`` and ``batch(coef (s, p), z (s, n, c), y (s, n))``.

    On a CPU ``single`` is the compiled loop of :mod:`fogbayes.thermal.compensate_loops` and also
    takes ``out=`` (written in place); elsewhere it is the jitted XLA program."""

    single: Callable
    batch: Callable


@lru_cache(maxsize=128)
def _xla_programs(terms: tuple[tuple[int, ...], ...]):
    """XLA compensators of one term set, ``(single, batch)``: ``f(coef, z, y, centre,
    scale)``. The basis's centre and scale are arguments, so every calibration with these
    terms (every sensor of a fleet) shares one program per shape."""

    def one(coef, z, y, centre, scale):
        # The polynomial term by term, not ``design(z) @ coef``: XLA fuses this into one
        # loop over the samples instead of building the (n, p) design matrix and reducing
        # it (2.5-4x faster, benchmarks/RESULTS_stream.md). The terms are summed in order
        # and scaled by 1/scale, so results differ from ``design(z) @ coef`` by a rounding
        # or two of each term (~3e-15 deg/h where terms reach 10 deg/h).
        coef = coef.astype(y.dtype)
        centre, scale = centre.astype(y.dtype), scale.astype(y.dtype)
        zs = [(z[:, c] - centre[c]) * (1.0 / scale[c]) for c in range(z.shape[1])]
        acc = None
        for k, e in enumerate(terms):  # static: unrolled into one fused loop
            term = coef[k]
            for c, ec in enumerate(e):
                for _ in range(ec):
                    term = term * zs[c]
            acc = term if acc is None else acc + term
        return y - acc

    return program(one), program(jax.vmap(one, in_axes=(0, 0, 0, None, None)))


@lru_cache(maxsize=128)
def bias_compensator(basis: PolyBasis) -> Compensator:
    """The compensators of ``basis`` (built once; cached on the hashable basis)."""
    centre = np.asarray(basis.centre, dtype=float)
    scale = np.asarray(basis.scale, dtype=float)
    if jax_on_cpu():  # one pass at memory speed, no intermediate array, no compilation
        def single(coef, z, y, out=None, method="auto"):
            return compensate_into(basis, np.asarray(coef), np.asarray(z), np.asarray(y), out,
                                   method=method)
    else:
        def single(coef, z, y):
            return _xla_programs(basis.terms)[0](coef, z, y, centre, scale)

    def batch(coef, z, y):  # the term set's jit(vmap), compiled on its first call
        return _xla_programs(basis.terms)[1](coef, z, y, centre, scale)

    batch._cache_size = lambda: _xla_programs(basis.terms)[1]._cache_size()  # programs built
    return Compensator(single, batch)


def compensate_bias(coef, z, y, basis: PolyBasis, *, dtype=np.float64) -> np.ndarray:
    """Compensated output for one sensor (``y`` (n,), ``z`` (n, c)) or a batch (leading axis)."""
    coef, z, y = (np.asarray(a, dtype=dtype) for a in (coef, z, y))
    comp = bias_compensator(basis)
    f = comp.batch if y.ndim == 2 else comp.single
    return np.asarray(f(coef, z.reshape(y.shape + (-1,)), y))


def compensate_chunks(coef, basis: PolyBasis, chunks: Iterable[tuple[np.ndarray, np.ndarray]],
                      *, dtype=np.float64) -> Iterator[np.ndarray]:
    """Stream: compensate ``(z, y)`` chunks one after another with one compiled function.

    Chunks of equal length reuse one compilation; pad the last one (or accept one more).
    """
    for z, y in chunks:
        yield compensate_bias(coef, z, y, basis, dtype=dtype)
