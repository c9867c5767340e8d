"""Expected log predictive density (PSIS-LOO, WAIC) of a fitted model.

Pointwise: log N(v_t(beta_s); 0, s2 F_t), the Kalman one-step-ahead predictive of the block
means, beta_s ~ N(beta_hat, s2 S_XX^-1), noise at ML. Criteria as
:mod:`fogbayes.inference.compare`; where PSIS gives NaN, WAIC (stated in ``ic``).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..inference import compare as ic
from ..inference import noise_ssm as ns
from .context import Context
from .fitting import ModelFit


class Elpd(NamedTuple):
    elpd_loo: float
    se: float
    p_loo: float
    elpd_waic: float


def pointwise(ctx: Context, fit: ModelFit, *, n_draws: int = 100, seed: int = 0) -> np.ndarray:
    """(n_draws, n_obs) pointwise log-likelihood of the block means."""
    rng = np.random.default_rng(seed)
    nf = fit.noise
    cov = 0.5 * (nf.cov_beta + nf.cov_beta.T)
    betas = rng.multivariate_normal(nf.beta, cov, size=n_draws, method="eigh")
    return ns.pointwise_loglik(nf.spec, nf.theta, ctx.y, fit.X, ctx.grid.mask, ctx.grid.w,
                               betas, nf.sigma2)


def criteria(ctx: Context, fit: ModelFit, *, n_draws: int = 100, seed: int = 0,
        cache=None) -> tuple[ic.IC, ic.IC]:
    """PSIS-LOO and WAIC (pointwise) of ``fit``; ``cache`` (a dict) avoids recomputing a fit's."""
    key = (id(fit.noise), seed)
    if cache is not None and key in cache:
        return cache[key][1]
    ll = np.asarray(pointwise(ctx, fit, n_draws=n_draws, seed=seed), float)
    out = ic.information(ll, "loo"), ic.information(ll, "waic")
    if cache is not None:
        cache[key] = (fit, out)  # keep fit alive so its id is not reused
    return out


def elpd(ctx: Context, fit: ModelFit, *, n_draws: int = 100, seed: int = 0, cache=None) -> Elpd:
    """PSIS-LOO (and WAIC) of ``fit``; where PSIS fails (NaN) the WAIC value stands in."""
    lo, wa = criteria(ctx, fit, n_draws=n_draws, seed=seed, cache=cache)
    e = lo.elpd if np.isfinite(lo.elpd) else wa.elpd
    return Elpd(e, lo.se, lo.p, wa.elpd)


class ElpdDiff(NamedTuple):
    """elpd(with) - elpd(without) and its standard error, ``ic`` used."""

    diff: float
    se: float
    elpd_with: float
    elpd_without: float
    ic: str = "loo"


def compare(ctx: Context, with_fit: ModelFit, without_fit: ModelFit, *, n_draws: int = 100,
            seed: int = 0, cache=None) -> ElpdDiff:
    """The difference of two fits by PSIS-LOO and its standard error (pointwise, as
    ``az.compare``'s dse); where PSIS fails (a model far from the data gives wild importance
    weights: NaN) by WAIC instead."""
    a = criteria(ctx, with_fit, n_draws=n_draws, seed=seed, cache=cache)
    b = criteria(ctx, without_fit, n_draws=n_draws, seed=seed, cache=cache)
    k = 0 if np.isfinite(a[0].elpd) and np.isfinite(b[0].elpd) else 1
    diff, se = ic.difference(a[k], b[k])
    return ElpdDiff(diff, se, a[k].elpd, b[k].elpd, a[k].kind)
