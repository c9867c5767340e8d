"""Posterior of thermal coefficients: coverage of the truth, white vs AR noise, WAIC/LOO.

Coverage study (CI size; benchmarks/RESULTS_thermal.md has the larger one): 40 simulated
paper-004-like runs (room/-40/+60/room, 30 min soaks, 2 deg C/min ramps, 1 Hz; Shupe term;
noise white + flicker + Gauss-Markov 0.3 deg/h, 300 s: coloured), processed by the
workflow's own path (1 s blocks -> 60 s blocks, savgol dT/dt), model thermal (2, 2); 90 %
central intervals of the 5 coefficients vs the truth (200 intervals). Measured: AR(1)
noise 90.5 % with these seeds (91.0 % with seeds 200-239; 93.75 % over 80 other runs in
the benchmark); white noise 27 % (40.5 % in the benchmark). With 1 h
soaks and 1 deg C/min ramps: AR(1) 93-94 %, ARMA(1,1) 92.5 %, AR(2) 94 %, white 35 %.
"""

from __future__ import annotations

import numpy as np
import pytest

from fogbayes.inference.bayes import fit_linear_bayes, fit_linear_bayes_batch
from fogbayes.inference.compare import compare, loo, waic
from fogbayes.inference.lsq import lstsq
from fogbayes.models.polynomial import design, from_raw
from fogbayes.thermal.model import ThermalSpec, thermal_basis
from fogbayes.simulate import simulate
from fogbayes.thermal.data import coarser_blocks, fit_blocks, make_processing, sample_covariates

SPEC = ThermalSpec(2, 2)


def _run(seed):
    """Design, block means and true scaled-basis coefficients of one simulated run."""
    sim = simulate("paper004", seed=seed, soak=1800.0, ramp_rate=2.0,
                   noise={"N": 0.008, "B": 0.05, "markov": {"sigma": 0.3, "tau_c": 300.0}})
    rec, proc = sim.recording, make_processing("default")
    z = sample_covariates(rec, SPEC, proc)
    blocks = coarser_blocks(fit_blocks(rec, rec.rate("deg/h"), z, SPEC, proc, None), 60.0)
    basis = thermal_basis(SPEC, blocks.z)
    e = sim.truth.params["effects"]["paper004"]
    c, d, tr = e["c"], e["d"], e["T_ref"]
    # c0 + c1 (T - Tr) + c2 (T - Tr)^2 + d1 r + d2 r^2 in powers of T and r (origin 0)
    raw = {(0, 0): c[0] - c[1] * tr + c[2] * tr**2, (1, 0): c[1] - 2 * c[2] * tr, (2, 0): c[2],
           (0, 1): d[0], (0, 2): d[1]}
    truth = from_raw(np.array([raw[t] for t in basis.terms]), basis)
    return np.asarray(design(blocks.z, basis)), blocks.y, truth


@pytest.mark.slow
def test_ar_noise_intervals_cover_the_truth_and_white_noise_ones_do_not():
    runs = [_run(100 + k) for k in range(40)]
    n = min(r[1].size for r in runs)
    X = np.stack([r[0][:n] for r in runs])
    y = np.stack([r[1][:n] for r in runs])
    truth = np.stack([r[2] for r in runs])
    cover = {}
    for noise in ("ar", "white"):
        fit = fit_linear_bayes_batch(X, y, seed=0, noise=noise, p=1, num_warmup=300,
                                     num_samples=600, level=0.9)
        inside = (fit.interval[..., 0] <= truth) & (truth <= fit.interval[..., 1])
        cover[noise] = inside.mean()
        # R-hat < 1.01 and ESS >= 200 are strict for 2 x 600 draws: measured 87.5 % (ar)
        # and 82.5 % (white) of the sensors pass; a sampler failure would give ~0 %
        assert np.mean([c.converged for c in fit.convergence]) >= 0.6
    assert 0.85 <= cover["ar"] <= 0.95, cover  # measured 0.905 with these seeds
    assert cover["white"] < 0.6, cover  # measured 0.27: intervals ~3x too narrow


def _ar_data(n=220, phi=0.75, seed=1):
    rng = np.random.default_rng(seed)
    x = np.linspace(-1, 1, n)
    X = np.column_stack([np.ones(n), x, x**2, np.sin(3 * x)])
    e = np.zeros(n)
    a = 0.3 * rng.normal(size=n)
    for t in range(1, n):
        e[t] = phi * e[t - 1] + a[t]
    return X, X @ np.array([5.0, 1.0, -2.0, 0.5]) + e


def _waic_numpy(ll):
    """WAIC (log scale) from pointwise log-likelihoods (draws, n), Gelman et al. 2014
    (ArviZ 0.x takes the variance over draws with ddof = 0)."""
    from scipy.special import logsumexp

    lppd = logsumexp(ll, axis=0) - np.log(ll.shape[0])
    p_waic = np.var(ll, axis=0)
    return float(np.sum(lppd - p_waic))


def test_white_and_ar_posteriors_against_references():
    X, y = _ar_data()
    # 220 x 4 and 300/500 draws: the AR sampler compiled here serves the LOO test below
    white = fit_linear_bayes(X, y, seed=0, noise="white", num_warmup=300, num_samples=500)
    ar = fit_linear_bayes(X, y, seed=0, noise="ar", p=1, num_warmup=300, num_samples=500)
    ols = lstsq(X, y)
    assert white.convergence.converged and ar.convergence.converged
    # white noise + a wide prior: the posterior is the OLS sampling distribution; Monte
    # Carlo error of a mean is sd / sqrt(ESS ~ 800) = 0.035 sd, of an sd ~2.5 %
    np.testing.assert_allclose(white.mean, ols.params, atol=0.15 * np.max(ols.stderr))
    np.testing.assert_allclose(white.sd, ols.stderr, rtol=0.1)
    # AR(1) noise: against statsmodels' exact MLE of the same regression with AR(1) errors
    # (measured: betas within 0.03 MLE se, phi 0.602 vs 0.567 +- 0.057 -- a posterior mean
    # of a skewed phi -- and posterior sd within 8 % of the MLE se)
    from statsmodels.tsa.arima.model import ARIMA

    mle = ARIMA(y, exog=X, order=(1, 0, 0), trend="n").fit()
    beta_mle, se_mle = mle.params[:4], mle.bse[:4]
    assert np.all(np.abs(ar.mean - beta_mle) < 0.2 * se_mle)
    assert abs(ar.noise["phi"][0] - mle.params[4]) < mle.bse[4]
    np.testing.assert_allclose(ar.sd, se_mle, rtol=0.2)
    assert np.median(ar.sd / white.sd) > 1.5  # white noise understates the uncertainty
    # WAIC from ArviZ equals the textbook formula on the same pointwise log-likelihoods
    ll = np.asarray(ar.idata.log_likelihood["y"]).reshape(-1, y.size)
    assert waic(ar.idata)["elpd"] == pytest.approx(_waic_numpy(ll), rel=1e-10)
    # the one-step-ahead densities of the AR model predict far better than white noise
    table = compare({"white": white.idata, "ar1": ar.idata}, ic="loo")
    assert table[0]["model"] == "ar1" and table[1]["elpd_diff"] > 4 * table[1]["dse"]
    assert loo(ar.idata)["pareto_k_max"] < 0.7


def test_order_selection_by_loo_under_ar_noise():
    from fogbayes.thermal.workflow import fit_recording

    # truth: order 2 in T and 1 in dT/dt; a linear-in-T model misses the curvature badly
    sim = simulate("paper004", seed=7, soak=1800.0, ramp_rate=2.0,
                   noise={"N": 0.008, "B": 0.05, "markov": {"sigma": 0.3, "tau_c": 300.0}})
    doc = fit_recording(sim.recording, model="thermal", orders="1-2,1", order_criterion="loo",
                        bayes_average_s=60.0, num_warmup=300, num_samples=500)
    sel = doc["order_selection"]
    assert sel["candidates"] == [[1, 1], [2, 1]] and sel["criterion"].startswith("elpd_loo")
    assert sel["best"] == [2, 1] and sel["scores"][1] > sel["scores"][0] + 5  # measured 82.1 vs 67.7


def _ar1_exact_loglik(r, phi, sigma):
    """Exact AR(1) log-likelihood in NumPy: r_1 ~ N(0, s2 / (1 - phi^2)), then
    r_t | r_(t-1) ~ N(phi r_(t-1), s2) (the independent reference of the Kalman terms)."""
    s2 = sigma ** 2
    v0 = s2 / (1 - phi ** 2)
    ll = -0.5 * (np.log(2 * np.pi * v0) + r[0] ** 2 / v0)
    e = r[1:] - phi * r[:-1]
    return ll - 0.5 * np.sum(np.log(2 * np.pi * s2) + e ** 2 / s2)


def test_a_record_of_another_length_in_the_bucket_reuses_the_sampler_exactly():
    """A single fit holds its blocks in bucket_length(n) (one compiled sampler for nearby
    lengths); the padded log density equals the unpadded one and the pointwise terms are the
    record's own (their sum per draw is the exact AR(1) likelihood of its residual)."""
    import jax
    import jax.numpy as jnp

    from fogbayes.inference import bayes as fb
    from fogbayes.models.buckets import bucket_length

    assert bucket_length(220) == bucket_length(210) == 224
    X, y = _ar_data()  # 220 blocks: the sampler compiled by the reference test above
    fit_linear_bayes(X, y, seed=0, noise="ar", p=1, num_warmup=300, num_samples=500)
    misses = fb._sampler.cache_info().misses
    Xs, ys = X[:210], y[:210]
    short = fit_linear_bayes(Xs, ys, seed=0, noise="ar", p=1, num_warmup=300, num_samples=500)
    assert fb._sampler.cache_info().misses == misses  # the 210-block record compiled nothing
    ll = np.asarray(short.idata.log_likelihood["y"])
    assert ll.shape[-1] == 210
    post = short.idata.posterior
    beta = np.asarray(post["beta"])[0, :3]
    phi, sigma = np.asarray(post["phi"])[0, :3, 0], np.asarray(post["sigma"])[0, :3]
    for k in range(3):
        ref = _ar1_exact_loglik(ys - Xs @ beta[k], phi[k], sigma[k])
        assert ll[0, k].sum() == pytest.approx(ref, rel=1e-10)
    # the density the sampler sees: padded with n_valid == the record alone (and gradients)
    rng = np.random.default_rng(3)
    value_and_grad = jax.jit(jax.value_and_grad(fb._log_density))  # one program, not ~50 ops
    for p_ar in (0, 1):
        u = {"beta": jnp.asarray(rng.normal(size=(1, 4))), "log_sigma": jnp.asarray([-0.5]),
             "u_ar": jnp.asarray(rng.normal(size=(1, p_ar))), "u_ma": jnp.zeros((1, 0))}
        Xb, yb = np.zeros((1, 224, 4)), np.zeros((1, 224))
        Xb[0, :210], yb[0, :210] = Xs, ys
        val, grad = value_and_grad(u, jnp.asarray(Xb), jnp.asarray(yb), 210, 10.0)
        ref, gref = value_and_grad(u, jnp.asarray(Xs[None]), jnp.asarray(ys[None]), 210, 10.0)
        assert float(val) == pytest.approx(float(ref), rel=1e-12)
        for key in u:
            np.testing.assert_allclose(grad[key], gref[key], rtol=1e-10, atol=1e-12)
