"""Five-term Allan model, extra terms, unit conversions and the AVAR covariance model."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import integrate

from fogbayes.allan.model import (
    ARCSEC_IN_URAD, AllanParams, avar, coefficients_from_params, markov_avar, noise_scales,
    params_from_coefficients, params_from_variance_coefficients, sinusoid_avar, term_avar,
    variance_coefficients,
)
from fogbayes.simulate.noise import allan_variance_model, markov_noise, sinusoid
from fogbayes.stats.allan import allan_deviation
from fogbayes.stats.allan_cov import covariance_tensors, expected_avar, mixture_moments


def test_paper_002_conversions_reproduce_its_printed_numbers():
    # sigma^2 = sum C_n^2 tau^n with the C_n printed in paper 002 (section 2)
    p = params_from_coefficients([1.1754e-5, 1.0228e-2, 3.835e-3, 1.196e-3, 1.827e-4])
    printed = {"N": 1.704e-4, "B": 5.776e-3, "K": 0.1243, "R": 0.9303, "Q": 6.786e-6}
    for name, value in printed.items():
        # C_n are printed with 4-5 digits (up to 3e-4 relative rounding) and the results
        # with 4 (the paper truncates N: 1.7047e-4 -> 1.704e-4; R 0.93016 -> 0.9303)
        assert getattr(p, name) == pytest.approx(value, rel=6e-4), name
    np.testing.assert_allclose(coefficients_from_params(p),
                               [1.1754e-5, 1.0228e-2, 3.835e-3, 1.196e-3, 1.827e-4], rtol=1e-12)


def test_five_terms_match_the_simulator_contract_and_read_at_their_taus():
    p = AllanParams(Q=0.3, N=0.02, B=0.05, K=0.4, R=2.0)
    tau = np.geomspace(0.01, 1e5, 50)
    np.testing.assert_allclose(avar(p, tau), allan_variance_model(tau, **p._asdict()), rtol=1e-13)
    # N at tau = 1 h, K at tau = 3 h, Q at tau = sqrt(3) s, R at tau = sqrt(2) h: classic
    terms = np.asarray(term_avar(p, np.array([math.sqrt(3.0), 3600.0, 10800.0, math.sqrt(2) * 3600])))
    assert math.sqrt(terms[0, 0]) == pytest.approx(p.Q)
    assert math.sqrt(terms[1, 1]) == pytest.approx(p.N)
    assert math.sqrt(terms[3, 2]) == pytest.approx(p.K)
    assert math.sqrt(terms[4, 3]) == pytest.approx(p.R)
    assert math.sqrt(terms[2, 0]) == pytest.approx(0.6643 * p.B, rel=1e-4)
    back = params_from_variance_coefficients(np.asarray(variance_coefficients(p)))
    np.testing.assert_allclose(back, p, rtol=1e-12)
    assert ARCSEC_IN_URAD == pytest.approx(4.8481368, rel=1e-7)


def _avar_from_psd(psd, tau):
    """Paper 002 eq. 4 (one-sided PSD form): 4 int S(f) sin^4(pi f tau) / (pi f tau)^2 df."""
    f = lambda x: psd(x) * np.sin(np.pi * x * tau) ** 4 / (np.pi * x * tau) ** 2  # noqa: E731
    brk = np.arange(1, 400) / tau  # the integrand's zeros: integrate between them
    val = sum(integrate.quad(f, a, b, limit=200)[0] for a, b in zip(np.r_[0, brk[:-1]], brk))
    return 2.0 * val  # S one-sided = 2 x two-sided


def test_markov_term_equals_its_psd_integral():
    sigma, tc = 2.0, 5.0
    psd = lambda f: 4 * sigma**2 * tc / (1 + (2 * np.pi * f * tc) ** 2)  # noqa: E731 (one-sided)
    for tau in (0.3, 5.0, 60.0):
        # quadrature to 1e-6 relative; the tail above 400/tau carries < 1e-4 of the value
        assert float(markov_avar(tau, sigma=sigma, tau_c=tc)) == pytest.approx(
            _avar_from_psd(psd, tau), rel=2e-4)


def test_markov_and_sinusoid_terms_against_simulated_records():
    fs, n = 10.0, 400_000
    y = markov_noise(n, fs, seed=3, sigma=1.0, tau_c=20.0)
    res = allan_deviation(y, fs, taus=(10, 100, 1000, 10000))
    model = np.asarray(markov_avar(res.tau, sigma=1.0, tau_c=20.0))
    # discrete sampling is exact at these taus up to O(1/(fs tau_c)); estimates have EDF >= ~20
    assert np.all(np.abs(np.log(res.var / model)) < 3 * np.sqrt(2 / res.edf) + 0.01)
    s = sinusoid(n, fs, amplitude=0.5, frequency=0.013)
    res = allan_deviation(s, fs, taus=(3, 17, 50, 230))
    np.testing.assert_allclose(res.var, sinusoid_avar(res.tau, amplitude=0.5, frequency=0.013),
                               rtol=0.02)  # deterministic; finite-record leakage ~1 %


def test_noise_scales_give_the_five_term_expectations():
    p = AllanParams(Q=0.2, N=0.03, B=0.1, K=0.5)
    fs = 50.0
    ms = np.array([1, 4, 64, 1024, 16384])
    s = np.asarray(noise_scales(p, fs))
    disc = sum(s[i] * expected_avar(ms, t) for i, t in enumerate(
        ("quantization", "white", "flicker", "rrw")))
    cont = np.asarray(avar(p, ms / fs))
    # exact except the random walk's +1/(6m) discreteness, negligible once K matters
    np.testing.assert_allclose(disc, cont, rtol=2e-3)


@pytest.mark.parametrize("noise", ["white", "rrw", "quantization"])
def test_covariance_model_matches_monte_carlo(noise):
    rng = np.random.default_rng(11)
    n, reps = 4096, 1500
    ms = np.array([1, 2, 4, 8, 16, 32, 64, 128, 256])
    gen = {"white": lambda: rng.normal(size=(reps, n)),
           "rrw": lambda: np.cumsum(rng.normal(size=(reps, n)), axis=1),
           "quantization": lambda: np.diff(rng.normal(size=(reps, n + 1)), axis=1)}[noise]()
    from fogbayes.stats.allan_kernels import allan_variance

    V = np.asarray(allan_variance(gen, tuple(int(m) for m in ms))[0])
    T = covariance_tensors(ms, n + 1 - 2 * ms)
    scales = np.array([noise == "quantization", noise == "white", 0.0, noise == "rrw"], float)
    mean, cov = (np.asarray(a) for a in mixture_moments(T, scales))
    np.testing.assert_allclose(V.mean(0), mean, rtol=0.06)  # MC se of the mean <= 2 %
    sd_ratio = V.std(0) / np.sqrt(np.diag(cov))
    assert np.all(np.abs(sd_ratio - 1) < 0.1)  # MC se of an sd with 1500 reps: ~2 %
    corr = cov / np.sqrt(np.outer(np.diag(cov), np.diag(cov)))
    mc = np.corrcoef(V.T)
    # adjacent-octave correlations: 0.4 (quantization), ~0.5 (white), ~0.88 (rrw); MC se ~0.03
    assert np.max(np.abs(np.diag(corr, 1) - np.diag(mc, 1))) < 0.1


def test_records_of_one_length_share_their_covariance_tensors_read_only():
    """The tensors depend on the tau grid only: two records of one length (a pool's units)
    get the same read-only arrays, equal to a fresh build of that grid."""
    from fogbayes.allan.data import prepare
    from fogbayes.stats.allan_cov import _tensors

    rng = np.random.default_rng(5)
    a, b = (prepare(rng.normal(size=4096), 10.0) for _ in range(2))
    assert a.tensors is b.tensors
    with pytest.raises(ValueError):
        a.tensors.T[0, 0, 0, 0] = 1.0
    fresh = _tensors.__wrapped__(tuple(int(m) for m in a.tensors.ms),
                                 tuple(float(c) for c in a.tensors.counts))
    for x, y in zip(a.tensors, fresh):
        np.testing.assert_array_equal(x, y)
