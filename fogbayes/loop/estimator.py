"""The published calibration: the chosen terms' coefficients by GLS under the noise model less
its random walk, the constant by IEEE Std 952, the covariance under the full noise model.

The loop decides which terms to add under its full noise model (white + flicker + Gauss-Markov +
random walk). Under a random walk, GLS weighs the record's differences: its estimate of a slow
temperature law follows whatever else is slow in the record, and on measured noise it ends
beyond the plain least-squares fit where the walk is weak (``benchmarks/RESULTS_study_random.md``,
"Which estimator"). So the coefficients are GLS under a *working* noise model without the walk
(maximum likelihood refit of the rest), which keeps the law anchored to the whole record's
levels, and their covariance is the sandwich under the full model (honest whatever the working
model): with L' = S_w^-1 X A, A = (X' S_w^-1 X)^-1 the working GLS map,

    beta = T y,   T' = L' (I - h e_j') + u e_j',   cov = s2 T S T'   (:func:`.constant.noise_gram`)

where the constant c_j is reset to the time average of the output less the other terms
(u the blocks' sample shares, h = X'u; :mod:`.constant`). Without a walk in the model the
working model is the full one and this is the IEEE constant of the GLS fit.

S and s2 are the full model's at its restricted-likelihood (REML) hyperparameters,
s2 = RSS / (n - p) (:func:`reml_noise`): ML profiles the design out and leaves too little of the
slow noise that the constant and the temperature law share, so its intervals cover too little
(the measured coverage: ``benchmarks/RESULTS_loop.md``, "The published covariance").
"""

from __future__ import annotations

import numpy as np

from .context import Context
from .fitting import ModelFit, fit_terms
from .reml import with_reml
from ..effects.terms import design
from ..inference import noise_ssm as ns
from .constant import intercept_column, noise_gram


def working(ctx: Context, fit: ModelFit) -> ModelFit:
    """``fit``'s terms refitted under its noise model less the random walk (GLS, noise by
    maximum likelihood); ``fit`` itself where the model has no walk."""
    spec = fit.noise.spec
    if not spec.random_walk:
        return fit
    return fit_terms(ctx, fit.terms, spec=spec._replace(random_walk=False), residual=False)


def reml_noise(ctx: Context, fit: ModelFit, cache: dict | None = None):
    """``fit.noise`` with its hyperparameters by REML on ``fit``'s design and
    s2 = RSS / (n - p) at them (:mod:`fogbayes.loop.reml`): the covariance's noise."""
    nf = with_reml(ctx, fit, cache).noise
    mask = ctx.grid.mask
    r = ns.gls(nf.spec, nf.theta, ctx.y, fit.X, mask, ctx.grid.w)
    n_obs, p = float(np.sum(mask > 0)), fit.X.shape[1]
    return nf._replace(sigma2=float(r.sigma2) * n_obs / max(n_obs - p, 1.0))


def publish(ctx: Context, fit: ModelFit, cov_noise=None) -> ModelFit:
    """``fit`` (GLS under the full noise model) as published: the module doc's coefficients
    and covariance, the residual of the compensated calibration run. ``cov_noise``: the
    full model's noise (spec, theta, sigma2) for the covariance, :func:`reml_noise` in the
    loop; ``fit.noise`` (ML) if None. The published noise model stays ``fit.noise``."""
    w_fit = working(ctx, fit)
    wn, full = w_fit.noise, fit.noise
    cn = full if cov_noise is None else cov_noise
    X, mask = fit.X, ctx.grid.mask
    Xw = ns.whiten(wn.spec, wn.theta, X, mask, ctx.grid.w)[0]
    A = np.linalg.pinv(Xw.T @ Xw)
    Lt = ns.whiten_transpose(wn.spec, wn.theta, Xw, mask, ctx.grid.w) @ A  # (nb, p)
    beta = np.array(wn.beta, float)
    res = ctx.rate - design(list(fit.terms), ctx.cov) @ beta
    Tt = Lt.copy()
    j = intercept_column(fit)
    if j is not None:
        shift = float(np.mean(res[ctx.grid.use & ~ctx.outlier]))
        beta[j] += shift
        res = res - shift  # the per-sample design is built once
        u = ctx.grid.count * mask
        u = u / u.sum()
        Tt[:, j] += u - Lt @ (X.T @ u)
    cov = cn.sigma2 * noise_gram(cn.spec, cn.theta, ctx.grid.w, Tt)
    return fit._replace(noise=full._replace(beta=beta, cov_beta=0.5 * (cov + cov.T)),
                        residual=res)
