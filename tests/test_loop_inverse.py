"""The loop's composite compensation inverts U = f(W) per sample, and says where it cannot.

Truth: outputs computed from known rates by the terms' closed forms; the inverse must give
the rates back, and NaN where no rate produces the output.
"""

from __future__ import annotations

import numpy as np

from fogbayes.composite.compensate import monotone_bounds
from fogbayes.preprocess.covariates import Covariates
from fogbayes.effects.terms import Term
from fogbayes.loop.compensate import rate_polynomial, solve_rate


def _cov(w, T=None):
    t = np.arange(w.size, dtype=float)
    T = np.full(w.size, 20.0) if T is None else T
    return Covariates(t, T[:, None], ("T",), np.zeros(w.size), w, float(t[-1]), None)


def test_inverse_of_a_quadratic_scale_and_nan_beyond_its_extremum():
    # f(W) = 3600 W - 100 W^2 deg/h (W deg/s): increasing up to W = 18, where f = 32 400
    terms = [Term("omega_poly", {"powers": [1, 2], "scale": 1.0})]
    beta = np.array([3600.0, -100.0])
    w_true = np.linspace(-10.0, 15.0, 11)
    u = 3600.0 * w_true - 100.0 * w_true ** 2
    got = solve_rate(terms, beta, _cov(w_true), u)
    # Halley to convergence: 1e-12 of full scale, far below any gyro's resolution
    np.testing.assert_allclose(got, w_true, rtol=0, atol=1e-10)
    u_bad = np.array([40000.0, 1000.0])  # above the maximum: no W gives it
    got_bad = solve_rate(terms, beta, _cov(np.zeros(2)), u_bad)
    assert np.isnan(got_bad[0]) and np.isfinite(got_bad[1])
    assert abs(got_bad[1] - (18.0 - np.sqrt(18.0 ** 2 - 10.0))) < 1e-9  # 100 W^2 - 3600 W + 1000 = 0


def test_inverse_with_asymmetry_temperature_scale_and_bias_terms():
    # U = 40 (1 + 2e-3 T') W + 0.2 |W| + 3e-4 W^3/100^2 + 5 T'^2 + 2 step: every kind of the
    # composite family at once, T varying per sample
    rng = np.random.default_rng(0)
    n = 400
    w_true = rng.uniform(-100, 100, n)
    T = rng.uniform(-20, 60, n)
    Tz = (T - 20.0) / 40.0
    ws = 100.0
    terms = [Term("intercept", {}),
             Term("omega_poly", {"powers": [1, 3], "scale": ws}),
             Term("omega_abs", {"scale": ws}),
             Term("omega_tpoly", {"channel": 0, "powers": [1], "centre": 20.0, "t_scale": 40.0,
                                  "scale": ws}),
             Term("tpoly", {"channel": 0, "powers": [2], "centre": 20.0, "scale": 40.0})]
    beta = np.array([1.0, 4000.0, 30.0, 20.0, 8.0, 5.0])
    z = w_true / ws
    u = 1.0 + 4000.0 * z + 30.0 * z ** 3 + 20.0 * np.abs(z) + 8.0 * z * Tz + 5.0 * Tz ** 2
    got = solve_rate(terms, beta, _cov(w_true, T), u)
    np.testing.assert_allclose(got, w_true, rtol=0, atol=1e-9)
    # the per-sample polynomial reproduces the design at the true rates on both sides
    a0, pos, neg, scale = rate_polynomial(terms, beta, _cov(w_true, T))
    A = np.where((w_true >= 0)[:, None], pos, neg)
    back = a0 + sum(A[:, m] * z ** (m + 1) for m in range(A.shape[1]))
    np.testing.assert_allclose(back, u, rtol=1e-13, atol=1e-9)
    assert scale == ws


def test_monotone_bounds_are_the_folds_of_the_derivative():
    # w P(w) = w - w^3 / 3: derivative 1 - w^2, folds at -1 and +1 (times 1 - margin)
    lo, hi = monotone_bounds(np.array([[1.0, 0.0, -1.0 / 3.0], [2.0, 0.0, 0.0]]), margin=0.0)
    np.testing.assert_allclose(lo, [-1.0, -10.0])
    np.testing.assert_allclose(hi, [1.0, 10.0])
    # w + w^2 / 2: derivative 1 + w, fold at -1 only
    lo, hi = monotone_bounds(np.array([[1.0, 0.5]]), margin=0.0)
    assert lo[0] == -1.0 and hi[0] == 10.0
