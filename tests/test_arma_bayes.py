"""NumPyro ARMA posterior and WAIC/LOO order comparison."""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np
import pytest

from fogbayes.arma import bayes as arma_bayes
from fogbayes.arma.bayes import arma_posterior, compare_orders_bayes, pointwise_loglik
from fogbayes.arma.fit import fit_arma
from fogbayes.arma.model import arma_loglik

sm_proc = pytest.importorskip("statsmodels.tsa.arima_process")


def _sim(phi, theta, n, seed):
    return sm_proc.arma_generate_sample(np.r_[1, -np.asarray(phi)], np.r_[1, -np.asarray(theta)],
                                        n, distrvs=np.random.default_rng(seed).standard_normal)


@pytest.mark.slow
def test_posterior_matches_mle_and_converges():
    x = _sim([0.6], [-0.4], 600, 0)
    post = arma_posterior(x, p=1, q=1, seed=1, num_warmup=500, num_samples=500, num_chains=4)
    mle = fit_arma(jnp.array(x), p=1, q=1)
    assert post.converged, (post.rhat_max, post.ess_bulk_min, post.divergences)
    draws = post.idata.posterior
    sd_phi = float(draws["phi"].std())
    # flat prior on the PACF, n = 600: posterior mean and MLE differ by O(1/n), a small
    # fraction of a posterior SD; posterior SD ~ asymptotic SE (within 25 %)
    assert abs(float(post.phi[0]) - float(mle.phi[0])) < 0.3 * sd_phi
    assert sd_phi == pytest.approx(float(mle.se_phi[0]), rel=0.25)
    assert float(post.sigma2) == pytest.approx(float(mle.sigma2), rel=0.05)


def test_pointwise_terms_sum_to_the_exact_likelihood():
    x = jnp.array(_sim([0.5, -0.3], [0.2], 200, 3))
    phi = jnp.array([[0.5, -0.3], [0.1, 0.2]])
    theta = jnp.array([[0.2], [-0.4]])
    s2 = jnp.array([1.0, 1.7])
    pw = pointwise_loglik(phi, theta, s2, x)
    for i in range(2):
        ll = float(arma_loglik(phi[i], theta[i], s2[i], x))
        assert float(pw[i].sum()) == pytest.approx(ll, rel=1e-11)  # Kalman vs exact form


@pytest.mark.slow
def test_waic_and_loo_prefer_the_true_order():
    x = _sim([0.5, -0.4], [], 500, 5)
    # 2 x 1000 draws: with 2 x 300, R-hat < 1.01 failed by chance for about a third of the
    # posteriors (old MCMC-object sampler and the cached one alike, over seeds)
    c = compare_orders_bayes(x, [(1, 0), (2, 0)], seed=2, num_warmup=500, num_samples=1000)
    assert c.elpd_waic[1] > c.elpd_waic[0] + 2 * c.se_waic[1] / 10  # AR(2) clearly better
    assert c.elpd_loo[1] > c.elpd_loo[0]
    # WAIC and PSIS-LOO agree closely on a well-behaved model; Pareto k small
    np.testing.assert_allclose(c.elpd_waic, c.elpd_loo, atol=0.5)
    assert np.all(c.pareto_k_max < 0.7)
    assert all(p.converged for p in c.posteriors)


@pytest.mark.filterwarnings("ignore::UserWarning:arviz")  # WAIC/LOO of 60 draws: rough
def test_warm_calls_reuse_the_compiled_sampler():
    # the series, the order masks and the prior scale are traced arguments: another series
    # of the same length (or of the same length bucket), another seed and every order inside
    # the same padded (P, Q) = (1, 1) run the sampler and the pointwise likelihood compiled
    # by the first call
    x = _sim([0.5], [0.3], 120, 7)
    kw = {"num_warmup": 30, "num_samples": 30, "num_chains": 2}
    first = arma_posterior(x, p=1, q=1, seed=0, **kw)
    traces, hits = dict(arma_bayes.TRACES), arma_bayes._sampler.cache_info().hits
    again = arma_posterior(x, p=1, q=1, seed=0, **kw)
    arma_posterior(1.5 * x[::-1], p=1, q=1, seed=1, **kw)
    c = compare_orders_bayes(x, [(1, 0), (0, 1), (1, 1)], seed=2, **kw)
    # a series of another length in the same bucket (120 and 116 are both held in 128)
    shorter = arma_posterior(_sim([0.5], [0.3], 116, 8), p=1, q=1, seed=3, **kw)
    assert arma_bayes.TRACES == traces
    assert arma_bayes._sampler.cache_info().hits == hits + 6
    assert shorter.idata.log_likelihood["x"].shape == (2, 30, 116)  # its own samples only
    # same seed, same draws; the masks switch the absent coefficient off
    np.testing.assert_array_equal(first.idata.posterior["phi"], again.idata.posterior["phi"])
    assert c.posteriors[0].idata.posterior["theta"].values.max() == 0.0
    assert c.posteriors[1].idata.posterior["phi"].values.max() == 0.0
