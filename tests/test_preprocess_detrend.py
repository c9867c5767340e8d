"""Polynomial detrending on a centred/scaled basis: exact polynomials, numpy.polyfit."""

from __future__ import annotations

import numpy as np
import pytest

from fogbayes.errors import FogbayesError, ShapeError, TooShortError
from fogbayes.preprocess import detrend


@pytest.mark.parametrize("t0", [0.0, 1.7e9])  # a Unix-time origin must not hurt
def test_removes_exact_cubic(t0):
    t = t0 + np.arange(1000) * 0.1  # 100 s
    # The polynomial is built from the stamps as stored (at t0 = 1.7e9 they carry 2.4e-7 s
    # of rounding, so t - t0 is not exactly k / 10, but x is an exact cubic in t either way).
    s = t - t0
    x = 2.0 - 3.0 * s + 0.5 * s**2 + 1e-3 * s**3  # values up to ~5e3
    d = detrend(x, t, 3)
    # Exact in real arithmetic; float64 on values ~5e3 leaves ~1e-12.
    assert np.max(np.abs(d.residual)) < 1e-10
    assert np.allclose(d.trend + d.residual, x, rtol=0, atol=1e-12)
    # The monomial coefficients in u = (t - t_ref) / t_scale reproduce the trend anywhere.
    assert np.allclose(d.evaluate(t), d.trend, rtol=0, atol=1e-10)
    assert d.t_ref == pytest.approx(t0 + 49.95) and d.t_scale == pytest.approx(49.95)


def test_high_order_is_well_conditioned():
    t = np.linspace(-3.0, 7.0, 500)
    coef = np.random.default_rng(0).normal(size=11)
    x = np.polynomial.polynomial.polyval((t - 2.0) / 5.0, coef)  # order 10 in scaled time
    d = detrend(x, t, 10)
    assert np.max(np.abs(d.residual)) < 1e-10
    assert np.allclose(d.coef, coef, rtol=0, atol=1e-9)  # t_ref = 2, t_scale = 5 here


def test_matches_numpy_polyfit_on_noisy_data():
    rng = np.random.default_rng(1)
    t = np.sort(rng.uniform(0, 3600, 2000))
    x = 5.0 + 0.01 * t + rng.normal(size=t.size)
    d = detrend(x, t, 2)
    ref = np.polyval(np.polyfit(t - 1800.0, x, 2), t - 1800.0)  # independent LSQ route
    assert np.allclose(d.trend, ref, rtol=0, atol=1e-9)
    assert np.allclose(detrend(x, t, 0).residual, x - x.mean(), rtol=0, atol=1e-12)


def test_mask_and_default_index():
    x = 1.0 + 2.0 * np.arange(20.0)
    x[7] += 100.0
    mask = np.zeros(20, bool)
    mask[7] = True
    d = detrend(x, None, 1, mask=mask)  # t = sample index
    assert np.allclose(d.trend, 1.0 + 2.0 * np.arange(20.0), rtol=0, atol=1e-12)
    assert d.residual[7] == pytest.approx(100.0)  # residual given for masked samples too


def test_errors():
    with pytest.raises(TooShortError, match="order 3 needs at least 4"):
        detrend(np.ones(3), np.arange(3.0), 3)
    with pytest.raises(ShapeError, match="t has 9"):
        detrend(np.ones(10), np.arange(9.0), 1)
    with pytest.raises(FogbayesError, match="order must be an integer"):
        detrend(np.ones(10), None, -1)
    with pytest.raises(ShapeError, match="mask has 5"):
        detrend(np.ones(10), None, 1, mask=np.zeros(5, bool))
