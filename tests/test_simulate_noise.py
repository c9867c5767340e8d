"""The simulator's noise has exactly the declared Allan parameters and statistics.

Allan deviations are computed with allantools.oadev (independent reference) and compared
with the closed forms of the five-term model. Each comparison accepts the estimate when
sigma_hat^2 / sigma^2 lies inside the central 99.9 % of chi2(edf) / edf, with the
equivalent degrees of freedom of Greenhall's algorithm (allantools.edf_greenhall) for the
noise type concerned; with <= 6 taus per test and fixed seeds this fails by chance with
probability < 1 % per test (and deterministically never, given the seeds). Measured over
100 seeds each: white, random-walk and quantization checks failed 0 of 100 times; the
flicker, combined, Gauss-Markov and ARMA checks 0 of 40 times (other seeds than these).
"""

from __future__ import annotations

import math

import allantools
import numpy as np
import pytest
from scipy import stats
from statsmodels.tsa.arima_process import arma_acovf

from fogbayes.errors import FogbayesError
from fogbayes.simulate import noise

FS = 10.0


def oadev2(x, m):
    _, ad, _, _ = allantools.oadev(x, rate=FS, data_type="freq", taus=np.asarray(m) / FS)
    return ad**2


def chi2_band(alpha, m, n, p=1e-3):
    """Central 1-p band of sigma_hat^2 / sigma^2 for an overlapping AVAR estimate."""
    edf = allantools.edf_greenhall(alpha=alpha, d=2, m=int(m), N=n + 1, overlapping=True)
    return stats.chi2.ppf(p / 2, edf) / edf, stats.chi2.ppf(1 - p / 2, edf) / edf


def assert_avar(x, m_list, alpha, expected):
    est = oadev2(x, m_list)
    for m, e, t in zip(m_list, est, expected):
        lo, hi = chi2_band(alpha, m, x.size)
        assert lo < e / t < hi, f"m={m}: ratio {e / t:.4f} outside chi2 band ({lo:.4f}, {hi:.4f})"


def test_white_noise_is_angle_random_walk():
    n, N = 100_000, 0.02  # deg/sqrt(h)
    x = noise.allan_noise(n, FS, seed=1, N=N)
    m = [1, 10, 100, 1000]
    assert_avar(x, m, 0, noise.allan_variance_model(np.array(m) / FS, N=N))
    # per-sample variance (60 N)^2 fs, chi2 with n-1 dof: 5-sigma band is +-5 sqrt(2/n) = 2.2 %
    assert x.var(ddof=1) == pytest.approx((60 * N) ** 2 * FS, rel=5 * math.sqrt(2 / n))


def test_rate_random_walk():
    n, K = 100_000, 0.5  # deg/h^1.5
    x = noise.allan_noise(n, FS, seed=2, K=K)
    m = [1, 10, 100, 1000]
    assert_avar(x, m, -2, noise.allan_variance_model(np.array(m) / FS, K=K))


def test_quantization():
    n, Q = 100_000, 0.3  # arcsec
    x = noise.allan_noise(n, FS, seed=3, Q=Q)
    m = [1, 10, 100, 1000]
    assert_avar(x, m, 2, noise.allan_variance_model(np.array(m) / FS, Q=Q))


def test_rate_ramp_is_exact():
    n, R = 5000, 20.0  # deg/h^2
    x = noise.allan_noise(n, FS, seed=0, R=R)
    m = np.array([1, 10, 100])
    # a ramp has identical cluster differences, so the estimate is exact to rounding
    np.testing.assert_allclose(oadev2(x, m), noise.allan_variance_model(m / FS, R=R), rtol=1e-9)


def test_flicker_floor_is_0664_B():
    n, B = 200_000, 0.05
    # the generator's exact expected ADEV (closed form over its Fourier bins) is flat at
    # 0.664 B within 1.5 % from tau = 4/fs to T/20 (measured: +1.5 % at m=4, -0.1 % at T/20)
    m = np.array([4, 16, 64, 256, 1024, 4096, n // 20])
    ratio = np.sqrt(noise.flicker_avar(m, n, FS, B=B)) / (math.sqrt(2 * math.log(2) / math.pi) * B)
    np.testing.assert_allclose(ratio, 1.0, atol=0.015)
    assert math.sqrt(2 * math.log(2) / math.pi) == pytest.approx(0.664, abs=5e-4)
    # and realisations agree with it: mean of 6 independent AVAR estimates; 6 x edf dof
    reps = np.array([oadev2(noise.allan_noise(n, FS, seed=s, B=B), m[:5]) for s in range(6)])
    expected = noise.flicker_avar(m[:5], n, FS, B=B)
    for j, mm in enumerate(m[:5]):
        edf = 6 * allantools.edf_greenhall(alpha=-1, d=2, m=int(mm), N=n + 1, overlapping=True)
        lo, hi = stats.chi2.ppf(5e-4, edf) / edf, stats.chi2.ppf(1 - 5e-4, edf) / edf
        assert lo < reps[:, j].mean() / expected[j] < hi  # measured ratios 0.999 ... 1.005


def test_all_terms_add_and_streams_are_independent():
    n = 4000
    args = dict(Q=0.1, N=0.01, B=0.02, K=0.3, R=5.0)
    total = noise.allan_noise(n, FS, seed=7, **args)
    parts = sum(noise.allan_noise(n, FS, seed=7, **{k: v}) for k, v in args.items())
    np.testing.assert_allclose(total, parts, rtol=0, atol=1e-12)


def test_combined_model_adev():
    # a FOG-like mix: each tau's dominant term sets the edf (white at short tau, flicker in
    # the middle, RRW at long); with the mixture we allow the chi2 band of the weakest edf.
    n = 200_000
    args = dict(N=0.005, B=0.02, K=0.05)
    m = np.array([1, 10, 100, 1000, 10000])
    est = np.mean([oadev2(noise.allan_noise(n, FS, seed=s, **args), m) for s in range(4)], 0)
    model = noise.allan_variance_model(m / FS, **args)
    model_exact = model - noise.allan_variance_model(m / FS, B=args["B"]) \
        + noise.flicker_avar(m, n, FS, B=args["B"])
    for mm, e, t in zip(m, est, model_exact):
        edf = 4 * allantools.edf_greenhall(alpha=-2, d=2, m=int(mm), N=n + 1, overlapping=True)
        lo, hi = stats.chi2.ppf(5e-4, edf) / edf, stats.chi2.ppf(1 - 5e-4, edf) / edf
        assert lo < e / t < hi, (mm, e / t)
    # the closed form itself reproduces the five-term model's textbook slopes
    assert noise.allan_variance_model(100.0, N=1.0) / noise.allan_variance_model(1.0, N=1.0) \
        == pytest.approx(0.01)


def test_markov_variance_and_autocorrelation():
    n, sigma, tau_c = 200_000, 0.3, 2.0
    x = noise.markov_noise(n, FS, seed=4, sigma=sigma, tau_c=tau_c)
    a = math.exp(-1 / (FS * tau_c))
    # Var of the sample variance of an AR(1): (2 sigma^4 / n)(1 + a^2)/(1 - a^2); 5-sigma band
    rel = 5 * math.sqrt(2 / n * (1 + a * a) / (1 - a * a))  # = 0.10 here
    assert x.var() == pytest.approx(sigma**2, rel=rel)
    xc = (x - x.mean()) / x.std()
    for lag in (1, 5, 20, 50):
        r = np.mean(xc[:-lag] * xc[lag:])
        # Bartlett: Var r_j = [(1 + a^2)(1 - a^{2j})/(1 - a^2) - 2 j a^{2j}] / n; 5 sigma
        bart = ((1 + a * a) * (1 - a ** (2 * lag)) / (1 - a * a) - 2 * lag * a ** (2 * lag)) / n
        assert abs(r - math.exp(-lag / (FS * tau_c))) < 5 * math.sqrt(bart)


def test_markov_starts_stationary():
    # x_0 must already have variance sigma^2 (no warm-up transient): 3000 short records
    x0 = np.array([noise.markov_noise(2, FS, seed=s, sigma=2.0, tau_c=5.0)[0] for s in range(3000)])
    assert x0.var() == pytest.approx(4.0, rel=5 * math.sqrt(2 / 3000))  # 5 sigma = 13 %


def test_arma_autocovariance_matches_statsmodels():
    phi, theta, sigma = (0.6, -0.2), (0.4,), 0.5
    n = 200_000
    x = noise.arma_noise(n, seed=5, phi=phi, theta=theta, sigma=sigma)
    # statsmodels' MA polynomial is 1 + theta_sm L; the paper's is 1 - theta L
    ref = arma_acovf(np.r_[1, -np.array(phi)], np.r_[1, -np.array(theta)], nobs=4,
                     sigma2=sigma**2)
    got = np.array([np.mean(x[: n - k] * x[k:]) for k in range(4)])
    # sample autocovariances of a short-memory process: std ~ ref[0] sqrt(c / n) with c < 5
    # here (sum of squared autocorrelations); 5 sigma band = 5 * ref[0] * sqrt(5 / n) ~ 2.5 %
    np.testing.assert_allclose(got, ref, atol=5 * ref[0] * math.sqrt(5 / n))


def test_arma_starts_stationary():
    phi, theta = (0.9,), (0.3,)
    v0 = (1 + 0.3**2 - 2 * 0.9 * 0.3) / (1 - 0.81)  # = 2.89: a cold start would give 1.0
    x0 = np.array([noise.arma_noise(3, seed=s, phi=phi, theta=theta)[0] for s in range(3000)])
    assert x0.var() == pytest.approx(v0, rel=5 * math.sqrt(2 / 3000))


def test_arma_rejects_nonstationary():
    with pytest.raises(FogbayesError, match="not stationary"):
        noise.arma_noise(10, seed=0, phi=(1.1,))


def test_sinusoid_formula():
    n, A, f, ph = 1000, 0.7, 0.13, 0.4
    t = np.arange(n) / FS
    np.testing.assert_allclose(noise.sinusoid(n, FS, amplitude=A, frequency=f, phase=ph),
                               A * np.sin(2 * np.pi * f * t + ph), atol=1e-14)


@pytest.mark.parametrize("make", [
    lambda s: noise.allan_noise(500, FS, seed=s, Q=0.1, N=0.01, B=0.02, K=0.1),
    lambda s: noise.markov_noise(500, FS, seed=s, sigma=1.0, tau_c=3.0),
    lambda s: noise.arma_noise(500, seed=s, phi=(0.5,), theta=(0.2,)),
])
def test_seeds_reproduce(make):
    np.testing.assert_array_equal(make(11), make(11))
    assert not np.allclose(make(11), make(12))


def test_bad_arguments_raise_fogbayes_errors():
    with pytest.raises(FogbayesError, match="N must be"):
        noise.allan_noise(10, FS, seed=0, N=-1.0)
    with pytest.raises(FogbayesError, match="seed"):
        noise.allan_noise(10, FS, seed=-3, N=1.0)
    with pytest.raises(FogbayesError, match="n must be"):
        noise.allan_noise(0, FS, seed=0)
