"""Least squares: closed form vs statsmodels, optax vs closed form, nonlinear vs scipy."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from fogbayes.inference.lsq import fit_nonlinear, lstsq, lstsq_optax, minimize

sm = pytest.importorskip("statsmodels.api")


def _problem(seed=0, n=3000):
    rng = np.random.default_rng(seed)
    x = rng.uniform(-1, 1, n)
    X = np.column_stack([np.ones(n), x, x**2, x**3, rng.normal(size=n)])
    beta = np.array([-6652.0, 110.0, -3.0, 0.4, 2.0])  # PAN-like offset, FOG-like rest
    w = rng.uniform(0.5, 2.0, n)
    y = X @ beta + rng.normal(size=n) / np.sqrt(w) * 8.0
    return X, y, w


def test_closed_form_matches_statsmodels_wls():
    X, y, w = _problem()
    fit = lstsq(X, y, w)
    ref = sm.WLS(y, X, weights=w).fit()
    # both are exact solvers in float64 (QR vs pinv): agreement to ~1e-12 relative
    np.testing.assert_allclose(fit.params, ref.params, rtol=1e-10)
    np.testing.assert_allclose(fit.stderr, ref.bse, rtol=1e-9)
    np.testing.assert_allclose(fit.sigma2, ref.scale, rtol=1e-10)
    assert bool(fit.converged) and int(fit.dof) == X.shape[0] - X.shape[1]


def test_optax_agrees_with_closed_form():
    X, y, w = _problem(seed=1)
    a, b = lstsq(X, y, w), lstsq_optax(X, y, w)
    assert bool(b.converged) and int(b.n_iter) > 0
    # L-BFGS stops at |grad| < 1e-10 on the standardised problem: the parameters then
    # differ from the exact solution by far less than 1e-6 standard errors
    assert np.max(np.abs(np.asarray(a.params) - np.asarray(b.params)) / np.asarray(a.stderr)) < 1e-6
    np.testing.assert_allclose(b.covariance, a.covariance, rtol=1e-6, atol=1e-12)


def test_rank_deficient_design_is_not_converged():
    X, y, _ = _problem(n=200)
    X = np.column_stack([X, np.zeros(200)])  # e.g. dT/dt in a record without ramps
    fit = lstsq(X, y)
    assert not bool(fit.converged)
    assert np.all(np.isfinite(fit.params))  # minimum-norm solution: finite, not identified
    assert float(fit.params[-1]) == 0.0


def test_nonlinear_matches_scipy_curve_fit():
    scipy_opt = pytest.importorskip("scipy.optimize")
    rng = np.random.default_rng(3)
    t = np.linspace(0, 5, 400)
    y = 2.0 * (1 - np.exp(-t / 1.3)) + 0.05 * rng.normal(size=t.size)  # warm-up drift

    def model(t, a, tau):
        return a * (1 - np.exp(-t / tau))

    p_ref, cov_ref = scipy_opt.curve_fit(model, t, y, p0=(1.0, 1.0))
    fit = fit_nonlinear(lambda p: y - p["a"] * (1 - jnp.exp(-t / p["tau"])),
                        {"a": jnp.array(1.0), "tau": jnp.array(1.0)})
    assert bool(fit.converged)
    np.testing.assert_allclose([fit.params["a"], fit.params["tau"]], p_ref, rtol=1e-6)
    # both use s^2 (J^T J)^-1 at the optimum; Jacobians differ (AD vs finite differences)
    np.testing.assert_allclose(fit.covariance, cov_ref, rtol=1e-4)


def test_minimize_reports_non_convergence():
    rosen = lambda x: (1 - x[0]) ** 2 + 100 * (x[1] - x[0] ** 2) ** 2
    ok = minimize(rosen, jnp.array([-1.2, 1.0]), max_iter=500)
    assert bool(ok.converged)
    np.testing.assert_allclose(ok.params, [1.0, 1.0], atol=1e-6)
    short = minimize(rosen, jnp.array([-1.2, 1.0]), max_iter=3)
    assert not bool(short.converged) and int(short.n_iter) == 3


def test_vmap_over_sensors_equals_loop_and_compiles_once():
    X, y, w = _problem(n=500)
    ys = np.stack([y, 2 * y, y + 100.0])
    f = jax.jit(jax.vmap(lstsq, in_axes=(None, 0, None)))
    batch = f(X, ys, w)
    f(X, ys + 1.0, w)
    assert f._cache_size() == 1  # a second batch of the same shape reuses the compilation
    for k in range(3):
        np.testing.assert_allclose(batch.params[k], lstsq(X, ys[k], w).params, rtol=1e-12)


def test_normal_equations_path_equals_qr_in_a_scaled_basis():
    from fogbayes.inference.lsq import lstsq_gram

    X, y, w = _problem(seed=4)
    a, b = lstsq(X, y, w), lstsq_gram(X, y, w)
    # cond(X) ~ 5 here (centred basis): the squared condition costs ~2 digits of 16
    assert np.max(np.abs(np.asarray(b.params - a.params)) / np.asarray(a.stderr)) < 1e-8
    np.testing.assert_allclose(b.covariance, a.covariance, rtol=1e-9, atol=1e-15)
    assert bool(b.converged)


@pytest.mark.parametrize("rank_deficient", [False, True])
def test_numpy_inputs_take_the_same_qr_as_jax_inputs(rank_deficient):
    # concrete NumPy arrays are solved by LAPACK directly (no JAX dispatch); every field
    # must equal the JAX path's to rounding, including the rank-deficiency report
    rng = np.random.default_rng(4)
    X = rng.standard_normal((500, 4))
    if rank_deficient:
        X[:, 3] = X[:, 0] + X[:, 1]
    y = X @ np.array([1.0, -2.0, 0.5, 0.0]) + rng.standard_normal(500)
    w = rng.uniform(0.5, 2.0, 500)
    a, b = lstsq(X, y, w), lstsq(jnp.asarray(X), jnp.asarray(y), jnp.asarray(w))
    assert isinstance(a.params, np.ndarray) and bool(a.converged) == (not rank_deficient)
    assert bool(b.converged) == bool(a.converged)
    for name in ("params", "covariance", "stderr", "residual", "loss", "sigma2", "dof"):
        np.testing.assert_allclose(getattr(a, name), np.asarray(getattr(b, name)),
                                   rtol=1e-9, atol=1e-12, err_msg=name)
