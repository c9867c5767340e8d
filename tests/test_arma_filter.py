"""Kalman filter / RTS smoother, one-step prediction and denoising vs dense Gaussian algebra."""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np
import pytest
from scipy import linalg

from fogbayes.errors import ArgumentError
from fogbayes.arma.filter import (
    arma_spectrum,
    canonical_noise_var,
    denoise,
    one_step_prediction,
    signal_model,
)
from fogbayes.models.statespace import arma_state_space, kalman_filter, rts_smoother

sm_proc = pytest.importorskip("statsmodels.tsa.arima_process")
sm_arima = pytest.importorskip("statsmodels.tsa.arima.model")

MODELS = [([0.6], [], 1.0), ([-0.2699, -0.002968], [0.277], 1.75e-7), ([0.5, -0.3], [0.4], 2.0),
          ([0.9], [0.5], 1.0)]


def _acov(phi, theta, s2, n):
    return sm_proc.arma_acovf(np.r_[1, -np.asarray(phi)], np.r_[1, -np.asarray(theta)], nobs=n,
                              sigma2=s2)


def _sim(phi, theta, s2, n, seed):
    return sm_proc.arma_generate_sample(np.r_[1, -np.asarray(phi)], np.r_[1, -np.asarray(theta)],
                                        n, scale=np.sqrt(s2),
                                        distrvs=np.random.default_rng(seed).standard_normal)


@pytest.mark.parametrize("phi,theta,s2", MODELS)
def test_canonical_decomposition_reproduces_the_autocovariance(phi, theta, s2):
    """acov(signal) + h delta_k = acov(x), with statsmodels' ARMA autocovariances."""
    h = canonical_noise_var(phi, theta, s2)
    w = np.linspace(0, np.pi, 4097)
    assert h == pytest.approx(arma_spectrum(phi, theta, s2, w).min(), rel=1e-6)
    sp, sth, ss2 = signal_model(phi, theta, s2, h)
    gs = _acov(sp, sth, ss2, 30)
    gx = _acov(phi, theta, s2, 30)
    np.testing.assert_allclose(gs + h * (np.arange(30) == 0), gx, atol=1e-9 * gx[0])


@pytest.mark.parametrize("phi,theta,s2", MODELS)
def test_filter_and_smoother_equal_dense_conditioning(phi, theta, s2):
    n = 60
    x = _sim(phi, theta, s2, n, 4)
    d = denoise(phi, theta, s2, x)
    gs = _acov(d.signal_phi, d.signal_theta, d.signal_sigma2, n)
    Ss, h = linalg.toeplitz(gs), d.noise_var
    smooth = Ss @ np.linalg.solve(Ss + h * np.eye(n), x)  # E[s | x_1..x_n]
    filt = np.array([Ss[t, : t + 1] @ np.linalg.solve(Ss[: t + 1, : t + 1] + h * np.eye(t + 1),
                                                      x[: t + 1]) for t in range(n)])
    scale = np.abs(smooth).max()
    # exact algorithms both; the RTS gain uses a pseudo-inverse of a near-singular
    # predicted covariance (unit-circle MA root of the canonical signal): <= 1e-9 measured
    np.testing.assert_allclose(d.smoothed, smooth, atol=1e-8 * scale)
    np.testing.assert_allclose(d.filtered, filt, atol=1e-10 * scale)
    np.testing.assert_allclose(d.noise + d.smoothed, x, rtol=1e-12)


def test_smoothed_state_covariance_equals_dense_posterior():
    phi, theta, s2, h, n = [0.7], [0.2], 1.0, 0.5, 40
    x = _sim(phi, theta, s2, n, 8) + np.random.default_rng(9).normal(0, np.sqrt(h), n)
    ss = arma_state_space(jnp.array(phi), jnp.array(theta), s2)
    sm = rts_smoother(ss, kalman_filter(ss, jnp.array(x), obs_var=h))
    S = linalg.toeplitz(_acov(phi, theta, s2, n))
    post = S - S @ np.linalg.solve(S + h * np.eye(n), S)
    np.testing.assert_allclose(np.asarray(sm.cov[:, 0, 0]), np.diag(post), rtol=1e-9)


def test_one_step_prediction_equals_statsmodels():
    phi, theta, s2 = [0.5, -0.3], [0.4], 2.0
    # n in the 1 024-sample bucket of tests/test_arma_whiteness.py: its ARMA(2,1) filter
    x = _sim(phi, theta, s2, 1000, 2)
    one = one_step_prediction(np.array(phi), np.array(theta), s2, x)
    res = sm_arima.ARIMA(x, order=(2, 0, 1), trend="n").filter(np.r_[phi, -np.array(theta), s2])
    # same exact Kalman recursion; statsmodels stops updating P once converged (~1e-12)
    np.testing.assert_allclose(one.prediction, res.predict(), atol=1e-9)
    np.testing.assert_allclose(one.innovation_var, res.filter_results.forecasts_error_cov[0, 0],
                               rtol=1e-9)
    # standardised residuals have variance sigma2 and are (nearly) white
    assert np.var(one.residual) == pytest.approx(s2, rel=0.2)  # n = 1000: sd of var ~ 5 %


def test_denoise_rejects_impossible_noise_variance():
    with pytest.raises(ArgumentError, match="noise_var"):
        denoise([0.6], [], 1.0, np.zeros(20), noise_var=10.0)
    # white noise model: everything is noise, the signal is zero
    d = denoise([], [], 1.0, np.ones(5))
    assert np.all(d.smoothed == 0.0) and np.all(d.noise == 1.0)


@pytest.mark.parametrize("phi,theta,h", [([0.9], [0.3], 0.2), ([0.5, 0.2], [0.4], 0.0)])
def test_missing_tail_leaves_filter_smoother_and_likelihood_of_the_series(phi, theta, h):
    """n_valid: a series held in a longer array, its tail noise (not zeros) that the
    filter must treat as missing. Filter, RTS smoother and log-likelihood over t < n equal
    the plain ones of the series alone (to float64 round-off)."""
    rng = np.random.default_rng(4)
    x = rng.normal(size=500).cumsum() * 0.05 + rng.normal(size=500)
    ss = arma_state_space(jnp.array(phi), jnp.array(theta), 1.0)
    plain = kalman_filter(ss, jnp.array(x), h)
    held = kalman_filter(ss, jnp.array(np.r_[x, 3.0 * rng.normal(size=76)]), h, n_valid=500)
    assert float(held.loglik) == pytest.approx(float(plain.loglik), rel=1e-13)
    for a, b in ((plain.filt_mean, held.filt_mean), (plain.innov, held.innov),
                 (rts_smoother(ss, plain).mean, rts_smoother(ss, held).mean),
                 (rts_smoother(ss, plain).cov, rts_smoother(ss, held).cov)):
        np.testing.assert_allclose(np.asarray(b)[:500], np.asarray(a), rtol=1e-12, atol=1e-14)


def test_one_step_prediction_of_nearby_lengths_compiles_one_filter():
    from fogbayes.arma.filter import _innovations

    x = np.random.default_rng(5).normal(size=1000)
    _innovations.clear_cache()
    for n in (900, 960, 1000):  # one bucket: 1024 (that of test_arma_whiteness.py's filters)
        one = one_step_prediction([0.5], [0.2], 1.0, x[:n])
        assert one.residual.shape == (n,)
    assert _innovations._cache_size() == 1


def test_the_one_filter_on_a_diagonal_system_with_missing_samples_equals_dense_conditioning():
    """The noise model's system (two first-order states, a random walk from 0, observed
    through their sum, time-varying white variance, samples missing by the mask) on two
    columns: innovations and variances equal the dense Gaussian predictions from the observed
    past (covariance built from the model's recursion, not the filter's)."""
    from fogbayes.models.statespace import linear_gaussian_filter

    rng = np.random.default_rng(7)
    n = 40
    phi = np.array([0.3, 0.9, 1.0])
    q = np.array([0.5, 0.2, 0.05])
    p0 = np.array([0.5 / (1 - 0.09), 0.2 / (1 - 0.81), 0.0])
    h = rng.uniform(0.5, 2.0, n)
    mask = (rng.uniform(size=n) > 0.2).astype(float)
    Y = rng.normal(size=(n, 2)) * mask[:, None]
    P, cov_states = np.diag(p0), []
    for _ in range(n):
        cov_states.append(P)
        P = np.diag(phi) @ P @ np.diag(phi) + np.diag(q)
    S = np.empty((n, n))
    for t in range(n):
        for s in range(t, n):
            S[t, s] = S[s, t] = (phi ** (s - t)) @ cov_states[t] @ np.ones(3)
    S += np.diag(h)
    V, F = linear_gaussian_filter(lambda M: jnp.asarray(phi)[:, None] * M, jnp.diag(q),
                                  jnp.ones(3), jnp.diag(p0), jnp.asarray(Y), jnp.asarray(h),
                                  jnp.asarray(mask), states=False)
    for t in range(n):
        past = np.flatnonzero(mask[:t] > 0)
        w = linalg.solve(S[np.ix_(past, past)], S[past, t]) if past.size else np.zeros(0)
        np.testing.assert_allclose(np.asarray(V)[t], Y[t] - w @ Y[past], rtol=1e-9, atol=1e-9)
        assert float(F[t]) == pytest.approx(S[t, t] - S[t, past] @ w, rel=1e-9)
