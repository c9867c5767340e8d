"""Temperature rate: hand-computed differences, exact ramps/polynomials, scipy's
Savitzky-Golay filter and the closed-form noise of both estimators."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.signal import savgol_filter

from fogbayes.errors import FogbayesError, ShapeError, TooShortError
from fogbayes.preprocess import temperature_rate, temperature_rate_per_min
from fogbayes.preprocess.temperature_rate import local_poly_slope, savgol_slope_grid


def test_difference_hand_computed():
    t = np.arange(6.0)
    T = t**2  # 0 1 4 9 16 25
    # 2 s blocks: means 0.5, 6.5, 20.5 at 0.5, 2.5, 4.5 -> rates 6/2 = 3 (at 1.5) and
    # 14/2 = 7 (at 3.5).
    interp = temperature_rate(t, T, window_s=2.0)
    # Linear between (1.5, 3) and (3.5, 7): t = 2 -> 3 + 0.5 * 2 = 4, t = 3 -> 3 + 1.5 * 2 = 6;
    # constant outside.
    assert interp.tolist() == [3.0, 3.0, 4.0, 6.0, 7.0, 7.0]
    hold = temperature_rate(t, T, window_s=2.0, align="hold")
    assert hold.tolist() == [3.0, 3.0, 3.0, 3.0, 7.0, 7.0]  # backward; first block forward
    assert temperature_rate_per_min(t, T, window_s=2.0).tolist() == [180.0, 180.0, 240.0,
                                                                     360.0, 420.0, 420.0]


def _jittered_gapped_time(seed=0):
    rng = np.random.default_rng(seed)
    dt = rng.uniform(0.8, 1.2, 2000)
    dt[[500, 1300]] += [120.0, 45.0]  # two gaps
    return np.cumsum(dt)


@pytest.mark.parametrize("method,align", [("difference", "interp"), ("difference", "hold"),
                                          ("savgol", "interp")])
def test_linear_ramp_exact_with_jitter_and_gaps(method, align):
    t = _jittered_gapped_time()
    T = -40.0 + (0.5 / 60.0) * t  # 0.5 deg C/min, paper 004's ramp
    r = temperature_rate(t, T, method=method, window_s=10.0, align=align)
    # A block mean of a line is the line at the mean time, and a local polynomial fit of a
    # line is the line: exact up to rounding of T ~ 40 (1e-14) over 10 s.
    assert r.shape == t.shape
    assert np.allclose(r, 0.5 / 60.0, rtol=1e-10, atol=0)


def test_savgol_exact_for_quadratic_on_irregular_time():
    t = _jittered_gapped_time(1)
    T = 20.0 + 0.01 * t - 2e-6 * t**2
    r = temperature_rate(t, T, method="savgol", window_s=15.0, polyorder=2)
    assert np.allclose(r, 0.01 - 4e-6 * t, rtol=0, atol=1e-10)


def test_local_fit_equals_scipy_savgol_on_a_grid():
    rng = np.random.default_rng(2)
    T = np.cumsum(rng.normal(size=500))
    t = 0.5 * np.arange(500)
    for w, p in [(11, 2), (21, 3), (5, 1)]:
        ref = savgol_filter(T, w, p, deriv=1, delta=0.5, mode="interp")
        # Two independent routes to the same least-squares slope; 1e-9 on values ~1.
        assert np.allclose(local_poly_slope(t, T, w, p), ref, rtol=0, atol=1e-9)


def test_fft_path_equals_scipy_savgol():
    # Long windows (e.g. 60 s at 200 Hz) are convolved by FFT with edge fits of their own;
    # force that path on windows scipy still handles directly and compare.
    y = 20.0 + 0.01 * np.cumsum(np.random.default_rng(4).normal(size=5000))
    for w, p in [(601, 2), (1001, 1), (701, 3)]:
        ref = savgol_filter(y, w, p, deriv=1, delta=0.1, mode="interp")
        # Measured max difference 2e-15 on slopes ~1e-2: FFT rounding of the de-meaned y.
        assert np.allclose(savgol_slope_grid(y, w, p, 0.1, direct_max=3), ref, rtol=0, atol=1e-12)


def test_rate_does_not_see_a_jump_across_a_gap():
    t = np.r_[np.arange(100.0), 500.0 + np.arange(100.0)]
    T = np.r_[20.0 + 0.02 * np.arange(100.0), 60.0 - 0.03 * np.arange(100.0)]  # +40 jump
    for method in ("difference", "savgol"):
        r = temperature_rate(t, T, method=method, window_s=10.0)
        assert np.allclose(r[:100], 0.02, rtol=1e-10) and np.allclose(r[100:], -0.03, rtol=1e-10)


def test_short_run_falls_back_to_its_slope():
    t = np.r_[np.arange(50.0), 200.0, 201.0, 202.0]  # a 3-sample run after a gap
    T = np.r_[np.zeros(50), 1.0, 1.5, 2.5]
    r = temperature_rate(t, T, window_s=10.0)
    # Least-squares slope of (200, 1), (201, 1.5), (202, 2.5): sum (t - 201)(T - 5/3) / 2
    # = (-1 * -2/3 + 1 * 5/6) / 2 = 0.75.
    assert np.allclose(r[50:], 0.75, rtol=1e-12) and np.allclose(r[:50], 0.0, atol=1e-15)


def test_noise_of_both_estimators_matches_closed_form():
    rng = np.random.default_rng(3)
    n, sigma, dt = 1_000_000, 0.05, 0.1
    t = dt * np.arange(n)
    T = 25.0 + sigma * rng.normal(size=n)
    # difference, hold: (mean of m - mean of m) / (m dt), sd = sqrt(2/m) sigma / (m dt).
    m = 100  # 10 s blocks
    r = temperature_rate(t, T, window_s=10.0, align="hold")[::m]
    sd_diff = np.sqrt(2 / m) * sigma / (m * dt)
    # 10 000 block values, neighbours correlated -1/2: the sd estimate has a standard error
    # of sqrt(1.5 / (2 * 10 000)) = 0.9 %; allow 4 % (> 4 se). Measured ratio 0.9988
    # (over 10 seeds at n = 2e5: mean 0.999, scatter 2.3 %, as predicted).
    assert r.std() == pytest.approx(sd_diff, rel=0.04)
    # savgol order 1 (= order 2 inside the record) over w samples is the regression slope:
    # sd = sigma / (dt sqrt(w (w^2 - 1) / 12)).
    w = 101
    r = temperature_rate(t, T, method="savgol", window_s=w * dt, polyorder=1)[w:-w:w]
    sd_sg = sigma / (dt * np.sqrt(w * (w**2 - 1) / 12))
    # ~9900 disjoint windows: se 0.7 %; measured ratio 1.0034.
    assert r.std() == pytest.approx(sd_sg, rel=0.04)


def test_bad_inputs():
    t = np.arange(100.0)
    T = np.zeros(100)
    with pytest.raises(TooShortError, match="shorter than the sample interval"):
        temperature_rate(t, T, window_s=0.5)
    with pytest.raises(TooShortError, match="2 blocks"):
        temperature_rate(t, T, window_s=60.0)  # two 60 s blocks do not fit in 100 s
    with pytest.raises(TooShortError, match="longer than the record"):
        temperature_rate(t, T, method="savgol", window_s=200.0)
    with pytest.raises(ShapeError, match="temperature has 99"):
        temperature_rate(t, T[:99])
    with pytest.raises(FogbayesError, match="unknown temperature-rate method"):
        temperature_rate(t, T, method="spline")
    with pytest.raises(FogbayesError, match="align"):
        temperature_rate(t, T, align="nearest")
    with pytest.raises(FogbayesError, match="polyorder"):
        temperature_rate(t, T, method="savgol", polyorder=0)
