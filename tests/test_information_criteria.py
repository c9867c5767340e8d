"""The one information-criterion module (fogbayes.inference.compare) against closed forms
and against ArviZ's own ``compare``: WAIC by its definition, PSIS-LOO close to exact
leave-one-out where that has a closed form, and the difference's standard error."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from scipy.special import logsumexp
from scipy.stats import norm

from fogbayes.inference.compare import difference, information, loglik_idata


def _normal_mean_loglik(y, sigma, draws, seed):
    """Pointwise log N(y_i; mu_s, sigma^2) for posterior draws mu_s of a normal mean
    (flat prior, sigma known): mu | y ~ N(ybar, sigma^2 / n)."""
    rng = np.random.default_rng(seed)
    mu = rng.normal(y.mean(), sigma / np.sqrt(y.size), size=draws)
    return norm.logpdf(y[None, :], mu[:, None], sigma), mu


def test_waic_is_its_definition():
    y = np.random.default_rng(1).normal(0.3, 1.0, 60)
    ll, _ = _normal_mean_loglik(y, 1.0, 2000, seed=2)
    w = information(loglik_idata(ll), "waic")
    lppd = logsumexp(ll, axis=0) - np.log(ll.shape[0])
    p_i = np.var(ll, axis=0)  # ArviZ's p_waic: variance over draws, ddof 0
    assert w.elpd == pytest.approx(float(np.sum(lppd - p_i)), rel=1e-12)
    assert w.p == pytest.approx(float(p_i.sum()), rel=1e-12)
    np.testing.assert_allclose(w.pointwise, lppd - p_i, rtol=1e-12)
    assert np.isnan(w.pareto_k_max)


def test_loo_close_to_exact_leave_one_out():
    """Normal mean, sigma known: p(y_i | y_-i) = N(ybar_-i, sigma^2 (1 + 1/(n-1))) exactly.
    With 4000 draws PSIS's Monte Carlo error is ~0.1 nats on the sum; 0.5 allows 5 of it."""
    n, sigma = 60, 1.0
    y = np.random.default_rng(3).normal(0.0, sigma, n)
    ll, _ = _normal_mean_loglik(y, sigma, 4000, seed=4)
    lo = information(loglik_idata(ll), "loo")
    m = (y.sum() - y) / (n - 1)
    exact = norm.logpdf(y, m, sigma * np.sqrt(1 + 1 / (n - 1)))
    assert lo.elpd == pytest.approx(float(exact.sum()), abs=0.5)
    assert lo.pareto_k_max < 0.7 and not lo.warning
    assert lo.p == pytest.approx(1.0, abs=0.3)  # one parameter


def test_difference_matches_arviz_compare():
    import arviz as az

    y = np.random.default_rng(5).normal(1.0, 1.0, 80)
    good, _ = _normal_mean_loglik(y, 1.0, 1000, seed=6)
    bad = norm.logpdf(y[None, :], np.zeros((1000, 1)), 1.0)  # a mean fixed at zero
    a, b = (information(loglik_idata(x), "loo") for x in (good, bad))
    d, se = difference(a, b)
    with warnings.catch_warnings():  # ArviZ 0.23 sorts with pandas' deprecated inplace=True
        warnings.filterwarnings("ignore", message=".*inplace keyword.*")
        table = az.compare({"good": a.data, "bad": b.data}, ic="loo")
    assert d == pytest.approx(float(table.loc["bad", "elpd_diff"]), rel=1e-10)
    assert se == pytest.approx(float(table.loc["bad", "dse"]), rel=1e-10)
    assert d > 2 * se  # a true mean of 1 over 80 points is found
    with pytest.raises(ValueError, match="cannot difference"):
        difference(a, information(loglik_idata(bad), "waic"))
