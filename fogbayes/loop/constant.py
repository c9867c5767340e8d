"""The calibration's constant is the IEEE Std 952 bias of the calibration run.

Under a noise model with a random walk started at zero (:mod:`fogbayes.inference.noise_ssm`),
the GLS intercept estimates the walk's *starting* level: whatever the first minutes of the
record do sets it. IEEE Std 952 defines the bias as the time average of the output; the
calibration constant is therefore taken as

    c = mean_i (y_i - sum_{j != 0} x_ij beta_j)       over the samples the fit used,

the GLS intercept plus the mean of its residual, so the compensated calibration run averages
to zero. The other coefficients stay GLS estimates.

Uncertainty. With r = y - X beta_GLS the GLS residual of the block means and u the blocks'
sample-count weights (sum 1), c = c_GLS + u'r. The GLS residual is uncorrelated with
beta_GLS (cov(beta, r) = s2 (X'S^-1X)^-1 X'S^-1 S (I - X A)' = 0), so

    var(c) = var(c_GLS) + var(u'r),   var(u'r) = s2 u'S u - (X'u)' cov(beta) (X'u),

with S the noise model's covariance of the block means (relative to s2): how much the
time average of a repeat of this run would scatter under the fitted noise. The
cross-covariances of c with the other coefficients are those of c_GLS.

u'S u is exact and O(n) per state component: a component x_{t+1} = phi x_t + e_t,
x_0 ~ N(0, p0), var(e) = q, contributes p0 (sum_t u_t phi^t)^2 + q sum_s G_s^2 with
G_s = sum_{t>s} u_t phi^(t-1-s); white noise contributes sum_t u_t^2 w_t.
"""

from __future__ import annotations

import numpy as np
from scipy.signal import lfilter

from ..inference.noise_ssm import system, unpack
from ..diagnose.context import Context
from ..diagnose.fitting import ModelFit


def intercept_column(fit: ModelFit) -> int | None:
    """Column index of the model's constant (the ``intercept`` term), None without one."""
    col = 0
    for tm in fit.terms:
        if tm.kind == "intercept":
            return col
        col += tm.n_cols
    return None


def mean_variance(spec, theta, w_white: np.ndarray, u: np.ndarray) -> float:
    """u' S u for the noise model ``(spec, theta)`` (relative to s2; module doc)."""
    import jax.numpy as jnp

    phi, q, p0 = (np.asarray(a, float) for a in system(spec, unpack(spec, jnp.asarray(
        theta, dtype=float))))
    u = np.asarray(u, float)
    total = float(np.sum(u * u * np.asarray(w_white, float)))
    n = u.size
    for ph, qj, pj in zip(phi, q, p0):
        if pj > 0:
            total += pj * float(np.sum(u * ph ** np.arange(n))) ** 2
        # G_s = u_{s+1} + phi G_{s+1}, G_{n-1} = 0: a first-order filter run backwards
        g = lfilter([1.0], [1.0, -ph], u[:0:-1])[::-1]
        total += qj * float(np.sum(g * g))
    return total


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
