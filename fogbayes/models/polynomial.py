"""Centred and scaled multivariate polynomial bases, and their raw coefficients.

z'_c = (z_c - centre_c) / scale_c, X[i, k] = prod_c z'_{i,c}^{e_{k,c}}, f(z) = X(z) @ coef.
Raw coefficients in powers of (z - origin) by the exact linear map raw = M @ coef (binomial
expansion; cov_raw = M cov M'), :func:`to_raw`, :func:`rebase_matrix`. Term sets must be
downward closed.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from functools import lru_cache
from math import comb
from typing import NamedTuple

import numpy as np

from ..support.xp import namespace

from ..errors import ShapeError


class PolyBasis(NamedTuple):
    """Static structure of a polynomial basis (hashable: usable as a jit static argument).

    Attributes:
        names: covariate names, e.g. ``("T", "dT/dt")``.
        terms: one exponent tuple per column, e.g. ``((0, 0), (1, 0), (0, 1))``.
        centre, scale: per covariate, ``z' = (z - centre) / scale``.
    """

    names: tuple[str, ...]
    terms: tuple[tuple[int, ...], ...]
    centre: tuple[float, ...]
    scale: tuple[float, ...]

    @property
    def n_terms(self) -> int:
        return len(self.terms)

    def labels(self) -> list[str]:
        """Human-readable term names, e.g. ``['1', 'T', 'T^2', 'T*dT/dt']``."""
        return [term_label(self.names, e) for e in self.terms]


def term_label(names: Sequence[str], exponents: Sequence[int]) -> str:
    parts = [n if e == 1 else f"{n}^{e}" for n, e in zip(names, exponents) if e > 0]
    return "*".join(parts) or "1"


def is_downward_closed(terms: Sequence[tuple[int, ...]]) -> bool:
    """True when every monomial's divisors are in the set too (needed for :func:`to_raw`)."""
    return _downward_closed(tuple(tuple(int(x) for x in e) for e in terms))


@lru_cache(maxsize=256)  # a fleet asks for the same term set once per sensor
def _downward_closed(terms: tuple[tuple[int, ...], ...]) -> bool:
    have = set(terms)
    for e in terms:
        for c, ec in enumerate(e):
            if ec > 0 and tuple(x - (i == c) for i, x in enumerate(e)) not in have:
                return False
    return True


def make_basis(names: Sequence[str], terms: Sequence[tuple[int, ...]], z: np.ndarray, *,
               centre: Sequence[float] | None = None,
               scale: Sequence[float] | None = None) -> PolyBasis:
    """A basis whose scaling maps the observed range of each covariate to [-1, 1].

    ``centre`` = mid-range and ``scale`` = half-range (1 where a covariate is constant, so
    that a zero temperature rate in a pure soak still gives a finite basis).
    """
    z = np.asarray(z, dtype=float)
    if z.ndim == 1:
        z = z[:, None]
    names, terms = tuple(names), tuple(tuple(int(x) for x in e) for e in terms)
    if z.shape[1] != len(names) or any(len(e) != len(names) for e in terms):
        raise ShapeError(f"{len(names)} covariate names, {z.shape[1]} covariate columns and "
                         f"terms of lengths {sorted({len(e) for e in terms})} do not match",
                         fix="give one name and one exponent per covariate column")
    if not _downward_closed(terms):
        raise ShapeError(f"the term set {terms} is not downward closed",
                         fix="include every lower-order monomial (e.g. T when T^2 is used)")
    mid, half = range_scaling(z.min(axis=0), z.max(axis=0))
    c = mid if centre is None else np.asarray(centre, dtype=float)
    s = half if scale is None else np.asarray(scale, dtype=float)
    return PolyBasis(names, terms, tuple(float(v) for v in c), tuple(float(v) for v in s))


def range_scaling(lo, hi) -> tuple[np.ndarray, np.ndarray]:
    """``centre = (lo + hi) / 2``, ``scale = (hi - lo) / 2`` (1 where that is 0), elementwise:
    the scaling :func:`make_basis` gives to covariates spanning ``[lo, hi]``."""
    lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
    half = (hi - lo) / 2
    return (lo + hi) / 2, np.where(half > 0, half, 1.0)


def design(z, basis: PolyBasis):
    """Design matrix ``X`` (n, p) of ``basis`` at covariates ``z`` (n, c); jnp, jit/vmap-able.

    Works in the dtype of ``z`` (float32 stays float32): the centring happens before any
    power is taken, which is what keeps single precision usable.
    """
    # NumPy in, NumPy out (no JAX dispatch for a workflow's concrete arrays); JAX otherwise
    xp = np if isinstance(z, np.ndarray) else namespace(z)
    z = xp.atleast_2d(xp.asarray(z).T).T  # (n,) -> (n, 1)
    zs = (z - xp.asarray(basis.centre, z.dtype)) / xp.asarray(basis.scale, z.dtype)
    cols = []
    for e in basis.terms:  # static, a handful of terms: unrolled at trace time
        col = xp.ones(z.shape[0], z.dtype)
        for c, ec in enumerate(e):
            if ec:
                col = col * zs[:, c] ** ec
        cols.append(col)
    return xp.stack(cols, axis=1)


def evaluate(coef, z, basis: PolyBasis):
    """``f(z) = X(z) @ coef`` for scaled-basis coefficients."""
    return design(z, basis) @ coef


def rebase_matrix(basis: PolyBasis, origin: Sequence[float] | None = None,
                  unit: Sequence[float] | None = None) -> np.ndarray:
    """Matrix ``M`` with ``coef_new = M @ coef`` for monomials in ``u_c = (z_c - origin_c) / unit_c``.

    ``origin = 0``, ``unit = 1`` gives the papers' raw coefficients. With
    ``z' = a u + b`` (``a = unit / scale``, ``b = (origin - centre) / scale``) each factor
    expands as ``(a u + b)^e = sum_j C(e, j) a^j b^(e-j) u^j``.
    """
    return rebase_matrices(basis.terms, np.asarray([basis.centre]), np.asarray([basis.scale]),
                           origin, unit)[0]


@lru_cache(maxsize=64)
def _expansion(terms: tuple[tuple[int, ...], ...]) -> list[tuple[int, int, tuple]]:
    """(row, column, ((c, C(e_c, j_c), j_c, e_c - j_c), ...)) for each monomial u^j in the
    binomial expansion of each scaled monomial z'^e (row = index of j, column = index of e)."""
    index = {e: k for k, e in enumerate(terms)}
    return [(index[j], k, tuple((c, comb(ec, jc), jc, ec - jc)
                                for c, (ec, jc) in enumerate(zip(e, j))))
            for k, e in enumerate(terms)
            for j in itertools.product(*(range(ec + 1) for ec in e))]


def rebase_matrices(terms, centre, scale, origin=None, unit=None) -> np.ndarray:
    """:func:`rebase_matrix` of many bases with the same ``terms`` at once: ``centre`` and
    ``scale`` (S, c) -> M (S, p, p) (a fleet's sensors each have their own scaling)."""
    centre = np.asarray(centre, dtype=float)
    scale = np.asarray(scale, dtype=float)
    S, nc = centre.shape
    origin = np.zeros(nc) if origin is None else np.asarray(origin, dtype=float)
    unit = np.ones(nc) if unit is None else np.asarray(unit, dtype=float)
    a = unit / scale  # (S, c)
    b = (origin - centre) / scale
    terms = tuple(tuple(int(x) for x in e) for e in terms)
    M = np.zeros((S, len(terms), len(terms)))
    for row, col, factors in _expansion(terms):
        w = np.ones(S)
        for c, binom, j, rest in factors:
            if j or rest:
                w = w * (binom * a[:, c] ** j * b[:, c] ** rest)
        M[:, row, col] += w
    return M


def to_raw(coef, basis: PolyBasis, cov=None, *, origin: Sequence[float] | None = None):
    """Scaled-basis coefficients -> coefficients of ``prod_c (z_c - origin_c)^j_c``.

    Returns the coefficients, or ``(coefficients, covariance)`` when ``cov`` is given.
    """
    M = rebase_matrix(basis, origin)
    raw = M @ np.asarray(coef, dtype=float)
    if cov is None:
        return raw
    return raw, M @ np.asarray(cov, dtype=float) @ M.T


def from_raw(raw, basis: PolyBasis, *, origin: Sequence[float] | None = None) -> np.ndarray:
    """Inverse of :func:`to_raw` (e.g. to load firmware coefficients into a basis)."""
    return np.linalg.solve(rebase_matrix(basis, origin), np.asarray(raw, dtype=float))
