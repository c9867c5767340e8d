"""The loop's composite compensation inverts U = f(W) per sample, and says where it cannot."""

from __future__ import annotations

import numpy as np

from fogbayes.diagnose.covariates import Covariates
from fogbayes.diagnose.terms import Term
from fogbayes.loop.compensate import INVERSE_TOL, solve_rate


def _cov(w):
    t = np.arange(w.size, dtype=float)
    return Covariates(t, np.full((w.size, 1), 20.0), ("T",), np.zeros(w.size), w,
                      float(t[-1]), None)


def test_inverse_of_a_quadratic_scale_and_nan_beyond_its_extremum():
    # f(W) = 3600 W - 100 W^2 deg/h (W deg/s): increasing up to W = 18, where f = 32 400
    terms = [Term("omega_poly", {"powers": [1, 2], "scale": 1.0})]
    beta = np.array([3600.0, -100.0])
    w_true = np.linspace(-10.0, 15.0, 11)
    u = 3600.0 * w_true - 100.0 * w_true ** 2
    got = solve_rate(terms, beta, _cov(w_true), u)
    # the accepted residual INVERSE_TOL (1 + |U|) deg/h, divided by the slope f'(W)
    slope = 3600.0 - 200.0 * w_true
    np.testing.assert_array_less(np.abs(got - w_true), INVERSE_TOL * (1 + np.abs(u)) / slope)
    u_bad = np.array([40000.0, 1000.0])  # above the maximum: no W gives it
    got_bad = solve_rate(terms, beta, _cov(np.zeros(2)), u_bad)
    assert np.isnan(got_bad[0]) and np.isfinite(got_bad[1])
    assert abs(got_bad[1] - (18.0 - np.sqrt(18.0 ** 2 - 10.0))) < 1e-9  # 100 W^2 - 3600 W + 1000 = 0
