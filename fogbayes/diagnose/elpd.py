"""Expected log predictive density (PSIS-LOO and WAIC by ArviZ) of a fitted model.

The pointwise log-likelihood is that of the block means' one-step-ahead predictive
densities from the Kalman filter (a prequential score: it respects the coloured noise),

    log p(ybar_t | ybar_<t, beta_s) = log N(v_t(beta_s); 0, s2 F_t),   v_t(beta) = v_t^y - V_t^X beta,

for draws beta_s from the GLS posterior N(beta_hat, s2 S_XX^-1) (flat prior), noise
hyperparameters at their ML values. ArviZ then gives elpd_loo with its standard error,
and ``az.compare`` the difference of two models with its own standard error (dse).
Where PSIS fails (NaN: a model far from the data gives wild importance ratios) the
comparison falls back to WAIC, and says so (``ic``).
"""

from __future__ import annotations

import warnings
from typing import NamedTuple

import numpy as np

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


def _idata(ll: np.ndarray):
    import arviz as az

    # ArviZ wants a posterior group beside the log-likelihood; a dummy draw index serves.
    return az.from_dict(posterior={"draw_index": np.arange(ll.shape[0], dtype=float)[None]},
                        log_likelihood={"y": ll[None]})


def loo(ctx: Context, fit: ModelFit, *, n_draws: int = 100, seed: int = 0, cache=None):
    """ArviZ PSIS-LOO (pointwise) of ``fit``; ``cache`` (a dict) avoids recomputing a fit's."""
    import arviz as az

    key = (id(fit.noise), seed)
    if cache is not None and key in cache:
        return cache[key][1]
    idata = _idata(pointwise(ctx, fit, n_draws=n_draws, seed=seed))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        out = az.loo(idata, pointwise=True)
        out.waic_elpd = float(az.waic(idata).elpd_waic)
    if cache is not None:
        cache[key] = (fit, out)  # keep fit alive so its id is not reused
    return out


def elpd(ctx: Context, fit: ModelFit, *, n_draws: int = 100, seed: int = 0, cache=None) -> Elpd:
    """PSIS-LOO (and WAIC) of ``fit``; where PSIS fails (NaN) the WAIC value stands in."""
    lo = loo(ctx, fit, n_draws=n_draws, seed=seed, cache=cache)
    e = float(lo.elpd_loo) if np.isfinite(lo.elpd_loo) else float(lo.waic_elpd)
    return Elpd(e, float(lo.se), float(lo.p_loo), float(lo.waic_elpd))


class ElpdDiff(NamedTuple):
    """elpd(with) - elpd(without) and its standard error (ArviZ ``compare``), ``ic`` used."""

    diff: float
    se: float
    elpd_with: float
    elpd_without: float
    ic: str = "loo"


def compare(ctx: Context, with_fit: ModelFit, without_fit: ModelFit, *, n_draws: int = 100,
            seed: int = 0, cache=None) -> ElpdDiff:
    """ArviZ ``compare`` of two fits by PSIS-LOO: difference and its standard error (dse)."""
    import arviz as az

    a = loo(ctx, with_fit, n_draws=n_draws, seed=seed, cache=cache)
    b = loo(ctx, without_fit, n_draws=n_draws, seed=seed, cache=cache)
    if np.isfinite(a.elpd_loo) and np.isfinite(b.elpd_loo):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            table = az.compare({"with": a, "without": b}, ic="loo")
        e_with = float(table.loc["with", "elpd_loo"])
        e_without = float(table.loc["without", "elpd_loo"])
        return ElpdDiff(e_with - e_without, float(table["dse"].max()), e_with, e_without, "loo")
    # PSIS failed (a model far from the data gives wild importance weights): WAIC instead
    wa, wb = _waic(ctx, with_fit, n_draws, seed), _waic(ctx, without_fit, n_draws, seed)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        table = az.compare({"with": wa, "without": wb}, ic="waic")
    e_with = float(table.loc["with", "elpd_waic"])
    e_without = float(table.loc["without", "elpd_waic"])
    return ElpdDiff(e_with - e_without, float(table["dse"].max()), e_with, e_without, "waic")


def _waic(ctx: Context, fit: ModelFit, n_draws: int, seed: int):
    import arviz as az

    idata = _idata(pointwise(ctx, fit, n_draws=n_draws, seed=seed))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return az.waic(idata, pointwise=True)
