"""Fit a list of terms to a Context's block means under the state-space noise model.

The regression coefficients are generalised-least-squares estimates and the noise
hyperparameters maximum-likelihood ones (:mod:`fogbayes.inference.noise_ssm`), so a fit
is the *profile* likelihood of the model: what the evidence compares.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..inference import noise_ssm as ns
from ..inference import noise_fit as nfit
from .context import Context
from ..effects.terms import Term, design


class ModelFit(NamedTuple):
    """A fitted model: its terms, block design, noise fit and per-sample residual (deg/h)."""

    terms: tuple[Term, ...]
    X: np.ndarray             # (nb, p) block design
    noise: nfit.NoiseFit
    residual: np.ndarray      # (n,) rate - X_full beta (deg/h)

    @property
    def loglik(self) -> float:
        return self.noise.loglik

    @property
    def beta(self) -> np.ndarray:
        return self.noise.beta

    @property
    def n_params(self) -> int:
        return self.X.shape[1] + self.noise.spec.n_theta + 1


def fit_terms(ctx: Context, terms, *, spec: ns.NoiseSpec | None = None, theta0=None,
              residual: bool = True) -> ModelFit:
    """GLS + ML noise fit of ``terms`` on the block means of ``ctx``.

    ``theta0`` (a previous fit's hyperparameters) is tried alongside the default starts.
    """
    terms = tuple(terms)
    spec = ctx.spec if spec is None else spec
    X = ctx.block_design(list(terms))
    extra = None
    if theta0 is not None and np.size(theta0) == spec.n_theta:
        extra = np.atleast_2d(theta0)
    nf = nfit.fit_noise(spec, ctx.y, X, ctx.grid.mask, ctx.grid.w, extra_starts=extra)
    res = ctx.rate - design(list(terms), ctx.cov) @ nf.beta if residual else np.zeros(0)
    return ModelFit(terms, X, nf, res)


def predict(fit: ModelFit, cov) -> np.ndarray:
    """Model value (deg/h) at every row of covariates ``cov``."""
    return design(list(fit.terms), cov) @ fit.beta
