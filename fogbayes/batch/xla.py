"""The vectorised fit's least squares and bias as ``jax.jit(jax.vmap(...))`` programs.

The equations of :mod:`.kernels` as one XLA program (GPU/TPU): ``"gram"``
(:func:`fogbayes.inference.lsq.lstsq_gram`) or ``"qr"`` (:func:`~fogbayes.inference.lsq.lstsq`);
rows of weight 0 get finite values; s^2 on each sensor's m_s - p degrees of freedom.
"""

from __future__ import annotations

from functools import lru_cache, partial

import jax
import jax.numpy as jnp
import numpy as np

from ..inference.lsq import lstsq, lstsq_gram
from ..models.polynomial import PolyBasis, design
from ..support.programs import program

SOLVERS = {"gram": lstsq_gram, "qr": lstsq}


def unit_basis(basis: PolyBasis) -> PolyBasis:
    """The same monomials with centre 0 and scale 1: applied to already-scaled covariates."""
    c = len(basis.names)
    return PolyBasis(basis.names, basis.terms, (0.0,) * c, (1.0,) * c)


def solve_one(z, y, w, centre, scale, n_valid, *, unit: PolyBasis, solver: str):
    """One sensor's weighted LSQ in its own scaled basis; dof from its own block count."""
    X = design((z - centre) / scale, unit)
    fit = SOLVERS[solver](X, y, w)
    dof = n_valid - unit.n_terms
    s2 = 2.0 * fit.loss / jnp.maximum(dof, 1.0)  # loss = wRSS / 2; padded rows add nothing
    cov = jnp.where(fit.sigma2 > 0, fit.covariance * (s2 / fit.sigma2), fit.covariance)
    return fit.params, cov, fit.residual, s2, dof, fit.converged & (dof > 0)


def _bias_one(coef, z, centre, scale, *, unit: PolyBasis):
    return design((z - centre) / scale, unit) @ coef


@lru_cache(maxsize=32)
def batched_solver(unit: PolyBasis, solver: str = "gram"):
    """``jit(vmap(solve))`` over sensors for one model structure (compiled once per shape)."""
    return program(jax.vmap(partial(solve_one, unit=unit, solver=solver)))


@lru_cache(maxsize=32)
def batched_bias(unit: PolyBasis):
    return program(jax.vmap(partial(_bias_one, unit=unit)))


def fit(z, y, w, centre, scale, n_valid, basis: PolyBasis, solver: str) -> tuple:
    """``kernels.fit_gram``'s results from the XLA program: z (S, c, m), y, w (S, m),
    centre/scale (S, c), n_valid (S,) -> coef, cov, rss, s2, dof, ok."""
    empty = w == 0
    zf = np.where(empty[:, None, :], centre[:, :, None], z).transpose(0, 2, 1)
    yf = np.where(empty, 0.0, y)
    coef, cov, resid, *rest = (np.asarray(a) for a in batched_solver(unit_basis(basis), solver)(
        *(jnp.asarray(a) for a in (zf, yf, w, centre, scale, n_valid))))
    return (coef, cov, np.sum(np.where(empty, 0.0, resid) ** 2, axis=1), *rest)


def bias(coef, Z, centre, scale, basis: PolyBasis, lo=None, hi=None) -> np.ndarray:
    """``kernels.evaluate``'s result from the XLA program (Z (S, c, n); optional clamp)."""
    if lo is not None:
        Z = np.clip(Z, lo[:, :, None], hi[:, :, None])
    return np.asarray(batched_bias(unit_basis(basis))(
        jnp.asarray(coef), jnp.asarray(Z.transpose(0, 2, 1)), jnp.asarray(centre),
        jnp.asarray(scale)))
