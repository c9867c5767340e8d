"""The linear-model posterior (fogbayes.inference.bayes) computes its convergence and the
thermal document's WAIC/LOO without ArviZ; ArviZ, given the same draws, is the reference:
R-hat (rank), bulk and tail ESS, and PSIS-LOO with the chains' relative efficiency."""

import warnings

import numpy as np
import pytest

az = pytest.importorskip("arviz")

from fogbayes.inference.bayes import fit_linear_bayes, fit_linear_bayes_batch  # noqa: E402
from fogbayes.inference.compare import information  # noqa: E402


def _data(n=200, K=1, seed=4):
    rng = np.random.default_rng(seed)
    x = np.linspace(-1, 1, n)
    X = np.column_stack([np.ones(n), x, x**2])
    e = np.zeros((K, n))
    for t in range(1, n):
        e[:, t] = 0.7 * e[:, t - 1] + 0.3 * rng.standard_normal(K)
    return X, X @ np.array([2.0, 1.0, -0.5]) + e


def test_convergence_and_loo_are_arviz_s_on_the_same_chains():
    X, y = _data()
    fit = fit_linear_bayes(X, y[0], seed=2, noise="ar", p=1, num_warmup=200,
                           num_samples=300, num_chains=2)
    idata = fit.idata  # built from the same arrays, on demand
    names = ["beta", "sigma", "phi"]
    rhat = max(float(np.max(az.rhat(idata, var_names=[v], method="rank")[v])) for v in names)
    bulk = min(float(np.min(az.ess(idata, var_names=[v], method="bulk")[v])) for v in names)
    tail = min(float(np.min(az.ess(idata, var_names=[v], method="tail")[v])) for v in names)
    c = fit.convergence
    assert c.r_hat_max == pytest.approx(rhat, rel=1e-10)
    assert c.ess_bulk_min == pytest.approx(bulk, rel=1e-10)
    assert c.ess_tail_min == pytest.approx(tail, rel=1e-10)
    ll = fit.groups["log_likelihood"]["y"].reshape(-1, y.shape[1])
    ours = information(ll, "loo", fit.relative_efficiency())
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ref = az.loo(idata, pointwise=True, scale="log")
    assert fit.relative_efficiency() != 1.0  # two chains: the efficiency is estimated
    assert ours.elpd == pytest.approx(float(ref.elpd_loo), rel=1e-11)
    assert ours.se == pytest.approx(float(ref.se), rel=1e-11)
    assert ours.p == pytest.approx(float(ref.p_loo), rel=1e-9)
    np.testing.assert_allclose(ours.pointwise, np.asarray(ref.loo_i), rtol=1e-11)
    assert ours.warning == bool(ref.warning)


def test_a_batch_reports_each_sensor_as_arviz_does():
    X, y = _data(K=3, seed=5)
    fit = fit_linear_bayes_batch(np.broadcast_to(X, (3,) + X.shape), y, seed=1, noise="white",
                                 num_warmup=200, num_samples=300, num_chains=2)
    rhat = az.rhat(fit.idata, var_names=["beta", "sigma"], method="rank")
    for k, c in enumerate(fit.convergence):
        worst = max(float(np.max(np.asarray(rhat["beta"])[k])), float(np.asarray(rhat["sigma"])[k]))
        assert c.r_hat_max == pytest.approx(worst, rel=1e-10)
