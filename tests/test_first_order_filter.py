"""The compiled first-order filter gives scipy.signal.lfilter's numbers to the last bit (the
reference: lfilter itself), for the AR(1) recursion, the first-order lag's coefficients and
an initial state, on one column, many and none."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.signal import lfilter

from fogbayes.support.first_order_filter import ar1_filter, first_order_filter


@pytest.mark.parametrize("shape", [(3600, 5), (1, 3), (0, 2), (7,)])
@pytest.mark.parametrize("phi", [0.0, 0.3, 0.9999, 1.0])
def test_ar1_is_lfilter(shape, phi):
    u = np.random.default_rng(2).normal(size=shape)
    np.testing.assert_array_equal(ar1_filter(phi, u), lfilter([1.0], [1.0, -phi], u, axis=0))


@pytest.mark.parametrize("tau", [0.5, 30.0, 1800.0])
def test_the_lag_coefficients_with_an_initial_state_are_lfilter(tau):
    u = 20.0 + np.cumsum(np.random.default_rng(3).normal(size=5000)) * 0.01
    a = float(np.exp(-1.0 / tau))
    c = float(-tau * np.expm1(-1.0 / tau))
    b = [1.0 - c, c - a]
    z0 = 21.5 - b[0] * u[0]
    want, _ = lfilter(b, [1.0, -a], u, zi=[z0])
    np.testing.assert_array_equal(first_order_filter(b[0], b[1], a, u, z0), want)


def test_varying_coefficient_recursion_equals_the_product_form():
    """y_k = sum_j (prod_{i=j+1..k} a_i) b_j, the closed form of the recursion."""
    from fogbayes.support.first_order_filter import varying_ar1

    rng = np.random.default_rng(5)
    a, b = rng.uniform(-1, 1, 30), rng.normal(size=30)
    want = [sum(np.prod(a[j + 1:k + 1]) * b[j] for j in range(k + 1)) for k in range(30)]
    np.testing.assert_allclose(varying_ar1(a, b), want, rtol=1e-12, atol=1e-14)
