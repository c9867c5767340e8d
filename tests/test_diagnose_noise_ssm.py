"""Kalman-filter GLS likelihood (fogbayes.inference.noise_ssm) against dense Gaussian algebra."""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np
import pytest

from fogbayes.loop import nullsim
from fogbayes.inference import noise_ssm as ns
from fogbayes.inference import noise_fit as nfit


def dense_cov(spec, theta, n, w):
    """Covariance of the noise model written out element by element (independent reference)."""
    phi, q, p0 = (np.asarray(a) for a in ns.system(spec, ns.unpack(spec, jnp.asarray(theta))))
    t = np.arange(n)
    S = np.diag(np.asarray(w, float))
    for j in range(phi.size):
        if phi[j] < 1.0:  # stationary AR(1): v phi^|t-u|
            S += p0[j] * phi[j] ** np.abs(t[:, None] - t[None, :])
        else:  # random walk from 0: q min(t, u)
            S += q[j] * np.minimum(t[:, None], t[None, :])
    return S


@pytest.fixture(scope="module")
def problem():
    rng = np.random.default_rng(3)
    n, dt = 160, 5.0
    spec = ns.make_spec(dt, n * dt, n_markov=1)
    theta = np.array([-1.0, -5.0, 0.3, np.log(60.0)])
    w = rng.uniform(0.5, 2.0, n)
    mask = np.ones(n)
    mask[40:55] = 0.0  # a gap: missing blocks
    t = np.arange(n) / n
    X = np.column_stack([np.ones(n), t, t ** 2])
    S = dense_cov(spec, theta, n, w)
    y = X @ [1.0, 2.0, 3.0] + np.linalg.cholesky(S) @ rng.standard_normal(n)
    return spec, theta, y, X, mask, w, S


def test_gls_matches_dense_generalised_least_squares(problem):
    spec, theta, y, X, mask, w, S = problem
    o = mask > 0
    So, Xo, yo = S[np.ix_(o, o)], X[o], y[o]
    Si = np.linalg.inv(So)
    beta = np.linalg.solve(Xo.T @ Si @ Xo, Xo.T @ Si @ yo)
    r = yo - Xo @ beta
    s2 = r @ Si @ r / o.sum()
    ll = -0.5 * (o.sum() * np.log(2 * np.pi * s2) + np.linalg.slogdet(So)[1] + o.sum())
    res = ns.gls(spec, theta, y, X, mask, w)
    # Same algebra in a different order: agreement to rounding (cond(S) ~ 1e3).
    assert res.loglik == pytest.approx(ll, rel=1e-10)
    np.testing.assert_allclose(res.beta, beta, rtol=1e-8)
    assert res.sigma2 == pytest.approx(s2, rel=1e-9)
    cov = s2 * np.linalg.inv(Xo.T @ Si @ Xo)
    np.testing.assert_allclose(res.cov_beta, cov, rtol=1e-7)


def test_gradient_based_fit_does_not_lose_to_the_truth(problem):
    spec, theta, y, X, mask, w, _ = problem
    fit = nfit.fit_noise(spec, y, X, mask, w)
    at_truth = ns.gls(spec, theta, y, X, mask, w).loglik
    assert fit.loglik >= at_truth - 1e-6  # the ML fit cannot be worse than the true values


def test_simulated_series_whiten_to_unit_white_noise():
    spec = ns.make_spec(4.0, 4000 * 4.0, n_markov=1)
    theta = np.array([-2.0, -9.0, 0.0, np.log(80.0)])
    n, B = 4000, 64
    w = np.ones(n)
    E = nullsim.simulate(spec, theta, 2.5, w, B, seed=0)
    W, _ = ns.whiten(spec, theta, E, np.ones(n), w)
    W = W / np.sqrt(2.5)
    # Innovations of data from the model are iid N(0, 1): mean square 1 within 4 standard
    # errors (sqrt(2 / (n B)) = 0.0028), lag-1 correlation within 4 / sqrt(n B) = 0.008.
    assert np.mean(W ** 2) == pytest.approx(1.0, abs=4 * np.sqrt(2 / (n * B)))
    r1 = np.sum(W[1:] * W[:-1]) / np.sum(W * W)
    assert abs(r1) < 4 / np.sqrt(n * B)


def test_column_logliks_equal_one_gls_per_column(problem):
    spec, theta, y, X, mask, w, _ = problem
    rng = np.random.default_rng(1)
    cols = np.column_stack([np.where(mask > 0, y, 0.0), rng.standard_normal((y.size, 2))])
    ll = nullsim.column_logliks(spec, theta[None], cols, X, mask, w)[0]
    ref = [ns.gls(spec, theta, cols[:, j], X, mask, w).loglik for j in range(3)]
    np.testing.assert_allclose(ll, ref, rtol=1e-10)


def test_flicker_bank_spans_the_record():
    spec = ns.make_spec(5.0, 20000.0)
    taus = np.asarray(spec.bank_taus)
    # from dt / 2 to twice the record (the simulated flicker has power down to 1 / T)
    assert taus[0] == pytest.approx(2.5)
    assert 40000.0 / np.sqrt(10.0) < taus[-1] <= 40000.0
    np.testing.assert_allclose(np.diff(np.log10(taus)), 0.5)  # half a decade apart


def test_restricted_likelihood_matches_dense_algebra(problem):
    import jax.numpy as jnp

    from fogbayes.loop.reml import _negreml_and_grad

    spec, theta, y, X, mask, w, S = problem
    o = mask > 0
    So, Xo, yo = S[np.ix_(o, o)], X[o], y[o]
    Si = np.linalg.inv(So)
    A = Xo.T @ Si @ Xo
    beta = np.linalg.solve(A, Xo.T @ Si @ yo)
    r = yo - Xo @ beta
    n = o.sum() - X.shape[1]
    s2 = r @ Si @ r / n  # REML: residual degrees of freedom
    # log L_R with s2 profiled; S is the covariance relative to s2, so |X' S^-1 X / s2|
    # and |s2 S| combine into the (n - p) log s2 of the module doc.
    ref = -0.5 * (n * np.log(2 * np.pi * s2) + np.linalg.slogdet(So)[1]
                  + np.linalg.slogdet(A)[1] + n)
    Xp, pad = ns.pad_columns(X)
    val, grad = _negreml_and_grad(spec, jnp.asarray(theta), jnp.asarray(np.where(o, y, 0.0)),
                                  jnp.asarray(Xp), jnp.asarray(mask), jnp.asarray(w),
                                  jnp.asarray(pad))
    assert -float(val) == pytest.approx(ref, rel=1e-10)
    assert np.all(np.isfinite(np.asarray(grad)))


def test_reml_gives_the_slow_noise_back_that_ml_loses():
    from fogbayes.loop.reml import reml_theta

    # Random walk + white with a slow design (cubic in time): ML lets the design take the
    # walk's power -- measured over these 16 records, 8 ML fits put the log walk ratio on
    # its lower bound (-22; truth -4) -- while REML counts the 4 degrees of freedom the
    # design uses: median -4.11, every record within [-6.6, -3.3].
    n, dt = 300, 10.0
    spec = ns.make_spec(dt, n * dt, flicker=False)
    truth = -4.0
    t = np.linspace(-1, 1, n)
    X = np.column_stack([t ** k for k in range(4)])
    ml, reml = [], []
    for seed in range(16):
        y = nullsim.simulate(spec, np.array([truth]), 1.0, np.ones(n), 1, seed=seed)[:, 0]
        fit = nfit.fit_noise(spec, y, X)
        ml.append(fit.theta[0])
        reml.append(reml_theta(fit, y, X, np.ones(n), np.ones(n))[0])
    ml, reml = np.array(ml), np.array(reml)
    assert np.sum(ml < truth - 10) >= 4  # ML collapses (the failure REML is here for)
    # REML: median within 0.5 (its sampling spread over 16 records is ~0.2), none collapsed
    assert abs(np.median(reml) - truth) < 0.5
    assert np.all(reml > truth - 4)
