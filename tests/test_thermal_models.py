"""Polynomial bases (centred/scaled <-> raw) and the thermal model's structure and covariates.

References: numpy.polynomial (raw evaluation), monomials written out by hand, and exact
temperature rates of linear ramps.
"""

from __future__ import annotations

import numpy as np
import pytest

from fogbayes.errors import MissingColumnError, ShapeError
from fogbayes.models.polynomial import (
    design,
    evaluate,
    from_raw,
    is_downward_closed,
    make_basis,
    rebase_matrix,
    to_raw,
)
from fogbayes.thermal.model import (
    OrderError,
    ThermalSpec,
    bias_t_spec,
    covariate_names,
    thermal_basis,
    thermal_covariates,
    thermal_terms,
)

RNG = np.random.default_rng(7)


def test_raw_coefficients_match_numpy_polyval():
    # T from -40 to 60 deg C: the raw cubic coefficients span ~1e0 ... 1e-6
    T = np.linspace(-40, 60, 201)
    b = make_basis(("T",), ((0,), (1,), (2,), (3,)), T)
    assert b.centre == (10.0,) and b.scale == (50.0,)
    coef = RNG.normal(size=4)
    raw = to_raw(coef, b)
    # float64 rounding of values of order 1: 1e-12 absolute is generous and still strict
    np.testing.assert_allclose(np.polynomial.polynomial.polyval(T, raw),
                               np.asarray(evaluate(coef, T[:, None], b)), atol=1e-12)
    np.testing.assert_allclose(from_raw(raw, b), coef, rtol=1e-10, atol=1e-12)


def test_multivariate_raw_form_about_an_origin():
    z = np.column_stack([RNG.uniform(-40, 60, 300), RNG.uniform(-1, 1, 300)])
    terms = ((0, 0), (1, 0), (2, 0), (0, 1), (0, 2), (1, 1))
    b = make_basis(("T", "dT/dt"), terms, z)
    coef = RNG.normal(size=len(terms))
    origin = np.array([25.0, 0.0])  # e.g. a firmware reference temperature
    about = rebase_matrix(b, origin) @ coef
    u = z - origin
    by_hand = sum(c * u[:, 0] ** e0 * u[:, 1] ** e1 for c, (e0, e1) in zip(about, terms))
    np.testing.assert_allclose(by_hand, np.asarray(evaluate(coef, z, b)), atol=1e-11)


def test_raw_covariance_is_the_linear_map():
    b = make_basis(("T",), ((0,), (1,), (2,)), np.array([[-10.0], [30.0]]))
    A = RNG.normal(size=(3, 3))
    cov = A @ A.T
    M = rebase_matrix(b)
    _, raw_cov = to_raw(np.zeros(3), b, cov)
    np.testing.assert_allclose(raw_cov, M @ cov @ M.T, rtol=1e-12)
    # Monte Carlo check of the same map (independent of the algebra): 4e5 draws give the
    # covariance to ~0.5 %; 3 % is > 5 Monte Carlo standard errors
    draws = RNG.multivariate_normal(np.zeros(3), cov, size=400_000) @ M.T
    np.testing.assert_allclose(np.cov(draws.T), raw_cov, rtol=0.03, atol=0.03 * np.abs(raw_cov).max())


def test_design_runs_in_float32_thanks_to_centring():
    T = np.linspace(-40.0, 85.0, 1000)
    b = make_basis(("T",), tuple((k,) for k in range(4)), T)
    x64 = np.asarray(design(T[:, None], b))
    x32 = np.asarray(design(T[:, None].astype(np.float32), b))
    assert x32.dtype == np.float32
    # centred values lie in [-1, 1]: float32 keeps ~1e-7 relative; raw T^3 ~ 6e5 would not
    np.testing.assert_allclose(x32, x64, atol=1e-6)


def test_term_sets():
    assert thermal_terms(ThermalSpec(2, 2)) == ((0, 0), (1, 0), (2, 0), (0, 1), (0, 2))
    assert (1, 1) in thermal_terms(ThermalSpec(2, 2, cross=True))
    assert len(thermal_terms(ThermalSpec(2, 2, cross=True))) == 6  # 1 T T^2 R R^2 TR
    assert thermal_terms(bias_t_spec(3)) == ((0,), (1,), (2,), (3,))
    spec = ThermalSpec(2, 1, extra=("temperature_2",), gradient=("temperature_2", "temperature"),
                       extra_order=2)
    assert covariate_names(spec) == ("T", "dT/dt", "temperature_2", "dT_gradient")
    terms = thermal_terms(spec)
    assert (0, 0, 2, 0) in terms and (0, 0, 0, 2) in terms and is_downward_closed(terms)
    assert spec.model == "thermal" and bias_t_spec(2).model == "bias-t"


def test_bad_structures_raise_specific_errors():
    with pytest.raises(ShapeError, match="downward closed"):
        make_basis(("T",), ((0,), (2,)), np.arange(5.0))
    with pytest.raises(OrderError, match="t_order"):
        thermal_basis(ThermalSpec(t_order=-1), np.zeros((4, 2)))


def test_covariates_of_a_linear_ramp():
    # two channels ramping at 0.5 and 0.3 deg C/min: every estimator is exact on a line
    t = np.arange(0.0, 3600.0, 1.0)
    temps = np.column_stack([20 + 0.5 * t / 60, 18 + 0.3 * t / 60])
    spec = ThermalSpec(2, 2, gradient=("temperature_2", "temperature"))
    for method in ("savgol", "difference", "paper"):
        z = thermal_covariates(t, temps, ("temperature", "temperature_2"), spec,
                               rate_method=method, rate_window_s=10.0)
        np.testing.assert_allclose(z[:, 1], 0.5, rtol=1e-9)  # deg C/min
    np.testing.assert_allclose(z[:, 0], temps[:, 0])
    np.testing.assert_allclose(z[:, 2], temps[:, 1] - temps[:, 0])


def test_missing_channel_names_the_fix():
    with pytest.raises(MissingColumnError, match="temperature_2"):
        thermal_covariates(np.arange(10.0), np.zeros((10, 1)), ("temperature",),
                           ThermalSpec(2, 0, extra=("temperature_2",)))
