"""Exact ARMA log-likelihood and the PACF reparameterisation against independent references."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy import linalg, stats

from fogbayes.arma.model import (
    ar_to_pacf,
    arma_acov,
    arma_loglik,
    arma_profile_loglik,
    pacf_to_ar,
)

sm_arima = pytest.importorskip("statsmodels.tsa.arima.model")
sm_proc = pytest.importorskip("statsmodels.tsa.arima_process")

# (phi, theta) in the paper's sign convention; the paper's ARMA(2,1) included
CASES = [
    ([0.5], []),
    ([0.5, -0.3], []),
    ([0.6, -0.2, 0.1], []),
    ([], [0.4]),
    ([0.7], [0.3]),
    ([-0.2699, -0.002968], [0.277]),
    ([0.5, 0.2], [0.6, -0.2, 0.1]),
    ([], []),
    ([0.3], [0.0]),  # theta_q = 0: singular stationary state covariance
    ([0.9], [0.8]),  # slowly decaying initial-state response
]


def _simulate(phi, theta, n, seed, scale=1.3):
    rng = np.random.default_rng(seed)
    return sm_proc.arma_generate_sample(np.r_[1, -np.asarray(phi)], np.r_[1, -np.asarray(theta)],
                                        n, scale=scale, distrvs=rng.standard_normal, burnin=500)


@pytest.mark.parametrize("phi,theta", CASES)
def test_loglik_matches_statsmodels(phi, theta):
    x = _simulate(phi, theta, 1500, seed=len(phi) * 10 + len(theta))
    sigma2 = 1.69
    model = sm_arima.ARIMA(x, order=(len(phi), 0, len(theta)), trend="n")
    # statsmodels writes the MA part with a plus sign: ma_sm = -theta
    ref = model.loglike(np.r_[phi, -np.asarray(theta), sigma2])
    for method in ("fast", "kalman"):
        ll = float(arma_loglik(jnp.array(phi), jnp.array(theta), sigma2, jnp.array(x), method=method))
        # issue's criterion 1e-8; both are exact float64 computations (measured <= 1e-11;
        # statsmodels stops updating its Riccati recursion once converged to ~1e-19)
        assert ll == pytest.approx(ref, rel=1e-8)


@pytest.mark.parametrize("phi,theta", [([0.6, -0.3], [0.5]), ([], [0.9, 0.2]), ([0.95], [])])
def test_loglik_matches_dense_gaussian(phi, theta):
    """Against the dense N(0, Toeplitz(acov)) with statsmodels' autocovariances (small n)."""
    n, sigma2 = 60, 0.7
    x = _simulate(phi, theta, n, seed=3)
    g = sm_proc.arma_acovf(np.r_[1, -np.asarray(phi)], np.r_[1, -np.asarray(theta)], nobs=n,
                           sigma2=sigma2)
    ref = stats.multivariate_normal(np.zeros(n), linalg.toeplitz(g)).logpdf(x)
    ll = float(arma_loglik(jnp.array(phi), jnp.array(theta), sigma2, jnp.array(x)))
    assert ll == pytest.approx(ref, rel=1e-10)  # both exact; float64 round-off only
    np.testing.assert_allclose(arma_acov(jnp.array(phi), jnp.array(theta), sigma2, 5), g[:5],
                               rtol=1e-10)


def test_profile_sigma2_is_the_maximiser():
    phi, theta = jnp.array([0.5]), jnp.array([0.3])
    x = jnp.array(_simulate([0.5], [0.3], 800, seed=5))
    lp, s2 = arma_profile_loglik(phi, theta, x)
    assert float(lp) == pytest.approx(float(arma_loglik(phi, theta, s2, x)), rel=1e-13)
    for f in (0.9, 1.1):  # any other sigma2 is worse
        assert float(arma_loglik(phi, theta, s2 * f, x)) < float(lp)


def test_gradients_fast_equal_kalman_and_finite_differences():
    """Gradient w.r.t. parameters and data (residual = data - model needs d/dx)."""
    x = jnp.array(_simulate([0.4, 0.2], [0.5], 300, seed=7))
    phi, theta = jnp.array([0.4, 0.2]), jnp.array([0.5])

    def f(method):
        return jax.grad(lambda a, b, s, y: arma_loglik(a, b, s, y, method=method),
                        argnums=(0, 1, 2, 3))(phi, theta, 1.1, x)

    fast, kal = f("fast"), f("kalman")
    for a, b in zip(fast, kal):
        np.testing.assert_allclose(a, b, rtol=1e-8, atol=1e-9)  # two exact algorithms
    eps = 1e-6  # central differences: error ~ eps^2 * third derivative << 1e-6
    e = jnp.zeros(2).at[1].set(eps)
    fd = (arma_loglik(phi + e, theta, 1.1, x) - arma_loglik(phi - e, theta, 1.1, x)) / (2 * eps)
    assert float(fast[0][1]) == pytest.approx(float(fd), rel=1e-6)


def test_vmap_equals_loop_and_compiles_once():
    xs = jnp.array(np.stack([_simulate([0.5], [0.2], 400, seed=s) for s in range(4)]))
    phis = jnp.array([[0.5], [0.3], [-0.2], [0.8]])
    thetas = jnp.array([[0.2], [0.1], [0.4], [-0.5]])
    f = jax.jit(jax.vmap(lambda a, b, y: arma_loglik(a, b, 1.0, y)))
    batched = f(phis, thetas, xs)
    loop = [float(arma_loglik(phis[i], thetas[i], 1.0, xs[i])) for i in range(4)]
    np.testing.assert_allclose(batched, loop, rtol=1e-12)
    f(phis + 0.01, thetas, xs)
    assert f._cache_size() == 1  # new values, same shapes: no recompilation


@pytest.mark.parametrize("seed", range(5))
def test_pacf_to_ar_is_stationary_and_matches_statsmodels_pacf(seed):
    rng = np.random.default_rng(seed)
    r = rng.uniform(-0.97, 0.97, size=4)
    phi = np.asarray(pacf_to_ar(jnp.array(r)))
    roots = np.roots(np.r_[-phi[::-1], 1.0])  # roots of 1 - sum phi_i z^i
    assert np.all(np.abs(roots) > 1.0)
    # the theoretical PACF of the AR(4) with these phi is r itself (statsmodels' own recursion)
    np.testing.assert_allclose(sm_proc.arma_pacf(np.r_[1, -phi], [1.0], lags=5)[1:], r, atol=1e-10)
    np.testing.assert_allclose(ar_to_pacf(jnp.array(phi)), r, atol=1e-12)


def test_pacf_to_ar_known_values_and_batch():
    # p = 2 by hand: phi_1 = r1 (1 - r2), phi_2 = r2
    np.testing.assert_allclose(pacf_to_ar(jnp.array([0.5, -0.2])), [0.6, -0.2], atol=1e-15)
    batch = pacf_to_ar(jnp.array([[0.5, -0.2], [0.1, 0.3]]))
    np.testing.assert_allclose(batch[1], [0.1 * 0.7, 0.3], atol=1e-15)
    assert pacf_to_ar(jnp.zeros(0)).shape == (0,)


@pytest.mark.parametrize("n", [1, 3])
@pytest.mark.parametrize("phi,theta", [([0.5, -0.2, 0.1], [0.4]), ([0.3], [0.5, 0.2, -0.1])])
def test_series_shorter_than_the_state(n, phi, theta):
    """n < r = max(p, q + 1): only part of the initial state is seen; still exact."""
    x = np.random.default_rng(n).standard_normal(n)
    g = sm_proc.arma_acovf(np.r_[1, -np.asarray(phi)], np.r_[1, -np.asarray(theta)], nobs=n,
                           sigma2=1.3)
    ref = stats.multivariate_normal(np.zeros(n), linalg.toeplitz(g)).logpdf(x)
    ll = float(arma_loglik(jnp.array(phi), jnp.array(theta), 1.3, jnp.array(x)))
    assert ll == pytest.approx(ref, rel=1e-12, abs=1e-12)


@pytest.mark.parametrize("phi,theta", [([0.5], [0.3]), ([0.4, 0.2], [0.5]), ([], [0.6, -0.2]),
                                       ([0.7], []), ([0.3, 0.2, -0.1], [0.5, 0.2, 0.1])])
def test_a_series_held_in_a_longer_array_has_its_own_likelihood(phi, theta):
    """n_valid: x_1..x_n of a longer array (the tail is noise, not zeros, so nothing hides a
    leak) gives the Kalman filter's exact log-likelihood of x_1..x_n alone; n = 3 is below
    the state dimension of the ARMA(3, 3)."""
    rng = np.random.default_rng(11)
    phi, theta = jnp.array(phi), jnp.array(theta)
    for n in (3, 57, 400):
        x = _simulate(np.asarray(phi), np.asarray(theta), n, seed=n)
        held = jnp.array(np.concatenate([x, 5.0 * rng.normal(size=77)]))
        lp, s2 = arma_profile_loglik(phi, theta, held, n_valid=n)
        ref = float(arma_loglik(phi, theta, s2, jnp.array(x), method="kalman"))
        assert float(lp) == pytest.approx(ref, rel=1e-11)
        assert float(s2) == pytest.approx(float(arma_profile_loglik(phi, theta, jnp.array(x))[1]),
                                          rel=1e-12)
