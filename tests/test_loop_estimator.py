"""The loop's published calibration (fogbayes/loop/estimator.py): coefficients by GLS under the
noise model less its random walk, the IEEE 952 constant, and a covariance that is the
estimator's scatter under the full noise model (walk included)."""

from __future__ import annotations

import numpy as np
import pytest

from fogbayes.loop.context import make_context
from fogbayes.loop.fitting import fit_terms
from fogbayes.loop.nullsim import simulate
from fogbayes.inference import noise_ssm as ns
from fogbayes.loop.bases import base_terms
from fogbayes.loop.constant import ieee_constant
from fogbayes.loop.estimator import publish, working
from fogbayes.loop.testbed import make_record


@pytest.fixture(scope="module")
def rec():
    return make_record("temperature_rate", seed=3, duration=2400.0, fs=1.0).recording


def test_whiten_transpose_is_the_adjoint_of_whiten(rec):
    ctx = make_context(rec)
    fit = fit_terms(ctx, base_terms(ctx, "bias-t"))
    rng = np.random.default_rng(1)
    n = ctx.grid.mask.size
    a, b = rng.normal(size=(n, 3)), rng.normal(size=(n, 3))
    sp, th = fit.noise.spec, fit.noise.theta
    wa = ns.whiten(sp, th, a, ctx.grid.mask, ctx.grid.w)[0]
    wtb = ns.whiten_transpose(sp, th, b, ctx.grid.mask, ctx.grid.w)
    assert np.sum(wa * b) == pytest.approx(np.sum(a * wtb), rel=1e-10)


def test_without_a_walk_it_is_the_ieee_constant_of_the_gls_fit(rec):
    ctx = make_context(rec, random_walk=False)
    fit = fit_terms(ctx, base_terms(ctx, "bias-t"))
    got, want = publish(ctx, fit), ieee_constant(ctx, fit)
    np.testing.assert_allclose(got.beta, want.beta, rtol=0, atol=1e-12)
    np.testing.assert_allclose(got.noise.cov_beta, want.noise.cov_beta, rtol=1e-8,
                               atol=1e-12 * np.abs(want.noise.cov_beta).max())


def test_the_covariance_is_the_estimators_scatter_under_the_full_noise_model(rec):
    """Monte Carlo under the fitted noise with its walk (hyperparameters fixed, as the
    covariance assumes): 400 series give each coefficient's sd to +-3.5 %; tolerance 12 %."""
    ctx = make_context(rec)
    fit = fit_terms(ctx, base_terms(ctx, "bias-t"))
    assert fit.noise.spec.random_walk
    se = np.sqrt(np.diag(publish(ctx, fit).noise.cov_beta))
    wn, nf = working(ctx, fit).noise, fit.noise
    mask, w, X = ctx.grid.mask, ctx.grid.w, fit.X
    m = 400
    Y = (X @ nf.beta)[:, None] + simulate(nf.spec, nf.theta, nf.sigma2, w, m, seed=11)
    V = ns.whiten(wn.spec, wn.theta, np.column_stack([Y * mask[:, None], X]), mask, w)[0]
    VX, VY = V[:, m:], V[:, :m]
    B = np.linalg.solve(VX.T @ VX, VX.T @ VY)  # (p, m) working-GLS estimates
    u = ctx.grid.count * mask
    u = u / u.sum()
    B[0] += u @ (Y - X @ B)  # the constant: the time average less the other terms
    np.testing.assert_allclose(np.std(B, axis=1, ddof=1), se, rtol=0.12)
    # the working model's own GLS covariance misses the walk's share of the scatter
    assert np.sqrt(np.diag(wn.cov_beta))[1:].max() < 0.8 * se[1:].max()


def test_the_published_covariance_uses_the_restricted_likelihood_noise(rec):
    """With white noise only the REML scale is RSS / (n - p): the temperature law's standard
    errors are weighted least squares' classical ones (statsmodels WLS on the same blocks)."""
    import statsmodels.api as sm

    from fogbayes.loop.estimator import reml_noise

    ctx = make_context(rec, random_walk=False, flicker=False)
    fit = fit_terms(ctx, base_terms(ctx, "bias-t"))
    assert fit.noise.spec.n_theta == 0
    se = np.sqrt(np.diag(publish(ctx, fit, cov_noise=reml_noise(ctx, fit)).noise.cov_beta))
    obs = ctx.grid.mask > 0
    ref = sm.WLS(ctx.y[obs], fit.X[obs], weights=1.0 / ctx.grid.w[obs]).fit()
    np.testing.assert_allclose(se[1:], ref.bse[1:], rtol=1e-8)
    # maximum likelihood's scale RSS / n is smaller by sqrt((n - p) / n)
    ml = np.sqrt(np.diag(publish(ctx, fit).noise.cov_beta))
    n, p = obs.sum(), fit.X.shape[1]
    np.testing.assert_allclose(ml[1:] / se[1:], np.sqrt((n - p) / n), rtol=1e-8)
