"""The calibration's constant is the IEEE Std 952 bias of the calibration run.

c = mean_i (y_i - sum_{j != 0} x_ij beta_j) = c_GLS + u'r (u the sample-count weights, r the GLS
residual); the other coefficients stay GLS. Since cov(beta_GLS, r) = 0,
var(c) = var(c_GLS) + s2 u'S u - (X'u)' cov(beta) (X'u), S the noise covariance of the block
means; u'S u is exact in O(n) per AR(1) component: p0 (sum_t u_t phi^t)^2 + q sum_s G_s^2,
G_s = sum_{t>s} u_t phi^(t-1-s), plus sum_t u_t^2 w_t for white noise.
"""

from __future__ import annotations

import numpy as np

from ..inference.noise_kalman import system
from ..support.first_order_filter import ar1_filter
from .context import Context
from .fitting import ModelFit


def intercept_column(fit: ModelFit) -> int | None:
    """Column index of the model's constant (the ``intercept`` term), None without one."""
    col = 0
    for tm in fit.terms:
        if tm.kind == "intercept":
            return col
        col += tm.n_cols
    return None


def noise_gram(spec, theta, w_white: np.ndarray, M: np.ndarray) -> np.ndarray:
    """M' S M for the noise model ``(spec, theta)`` (relative to s2; module doc), M (nb, k)."""
    phi, q, p0 = system(spec, theta)
    M = np.asarray(M, float).reshape(len(w_white), -1)
    total = M.T @ (M * np.asarray(w_white, float)[:, None])
    n = M.shape[0]
    for ph, qj, pj in zip(phi, q, p0):
        if pj > 0:
            a = (ph ** np.arange(n)) @ M
            total += pj * np.outer(a, a)
        # G_s = M_{s+1} + phi G_{s+1}, G_{n-2} = M_{n-1}: a first-order filter run backwards
        g = ar1_filter(ph, M[:0:-1])[::-1]
        total += qj * (g.T @ g)
    return total


def mean_variance(spec, theta, w_white: np.ndarray, u: np.ndarray) -> float:
    """u' S u for the noise model ``(spec, theta)`` (relative to s2; module doc)."""
    return float(noise_gram(spec, theta, w_white, np.asarray(u, float)[:, None])[0, 0])


def ieee_constant(ctx: Context, fit: ModelFit) -> ModelFit:
    """``fit`` with its constant set to the time average of the output less the other terms
    and its variance widened by the time average's scatter under the noise (module doc)."""
    j = intercept_column(fit)
    if j is None:
        return fit
    used = ctx.grid.use & ~ctx.outlier
    shift = float(np.mean(fit.residual[used]))
    nf = fit.noise
    beta = np.array(nf.beta, float)
    beta[j] += shift
    cov = np.array(nf.cov_beta, float)
    u = ctx.grid.count * ctx.grid.mask
    u = u / u.sum()
    xu = fit.X.T @ u
    var_mean = nf.sigma2 * mean_variance(nf.spec, nf.theta, ctx.grid.w, u) - xu @ cov @ xu
    cov[j, j] += max(float(var_mean), 0.0)
    return fit._replace(noise=nf._replace(beta=beta, cov_beta=cov),
                        residual=fit.residual - shift)
