"""Compensator (float32, batches, compile once) and coefficient export (JSON, PX4)."""

from __future__ import annotations

import numpy as np
import pytest
from jax import monitoring

from fogbayes.thermal.compensate import bias_compensator, compensate_bias, compensate_chunks
from fogbayes.export.coefficients import (
    DEG_H_TO_RAD_S,
    ExportError,
    px4_gyro_parameters,
    px4_param_file,
)
from fogbayes.models.basis_document import basis_from_dict, basis_to_dict, coefficient_document
from fogbayes.models.polynomial import evaluate, make_basis
from fogbayes.thermal.model import ThermalSpec, bias_t_spec, thermal_basis

RNG = np.random.default_rng(11)


def _cubic(n=20_000):
    T = np.linspace(-20.0, 60.0, n)
    basis = thermal_basis(bias_t_spec(3), T[:, None])
    coef = np.array([-6652.0, 450.0, 30.0, -8.0])  # deg/h, a PAN-sized MEMS bias
    return T, basis, coef


def test_float32_compensation_matches_float64():
    T, basis, coef = _cubic()
    y = np.asarray(evaluate(coef, T[:, None], basis)) + RNG.normal(size=T.size) * 50.0
    c64 = compensate_bias(coef, T[:, None], y, basis)
    c32 = compensate_bias(coef, T[:, None], y, basis, dtype=np.float32)
    assert c32.dtype == np.float32
    # float32 keeps 6e-8 relative of |y| ~ 7e3 deg/h: ~4e-4 deg/h, 1e5 x below the noise
    np.testing.assert_allclose(c32, c64, atol=2e-3)


def test_batch_equals_loop_and_compiles_once():
    T, basis, coef = _cubic(2000)
    coefs = np.stack([coef, 0.5 * coef, -coef])
    ys = RNG.normal(size=(3, T.size))
    z = np.broadcast_to(T[None, :, None], (3, T.size, 1))
    batch = compensate_bias(coefs, z, ys, basis)
    compensate_bias(coefs, z, ys + 1.0, basis)
    assert bias_compensator(basis).batch._cache_size() == 1
    for k in range(3):
        np.testing.assert_allclose(batch[k], ys[k] - np.asarray(evaluate(coefs[k], T[:, None], basis)),
                                   rtol=1e-12, atol=1e-9)
    # another calibration of the same terms (its own centre and scale): the same program
    other = basis._replace(centre=(basis.centre[0] + 5.0,), scale=(1.5 * basis.scale[0],))
    assert other.centre != basis.centre and other.scale != basis.scale
    traced = []

    def on_event(name, seconds, **kw):
        traced.append(name)

    monitoring.register_event_duration_secs_listener(on_event)
    try:
        again = compensate_bias(coefs, z, ys, other)
    finally:
        monitoring.unregister_event_duration_listener(on_event)
    assert "/jax/core/compile/jaxpr_trace_duration" not in traced  # nothing traced again
    for k in range(3):
        np.testing.assert_allclose(again[k], ys[k] - np.asarray(evaluate(coefs[k], T[:, None], other)),
                                   rtol=1e-12, atol=1e-9)


def test_streamed_chunks_equal_the_whole_record():
    T, basis, coef = _cubic(3000)
    y = RNG.normal(size=T.size)
    whole = compensate_bias(coef, T[:, None], y, basis)
    chunks = ((T[a:a + 1000, None], y[a:a + 1000]) for a in range(0, T.size, 1000))
    np.testing.assert_array_equal(np.concatenate(list(compensate_chunks(coef, basis, chunks))), whole)


def test_json_raw_coefficients_match_numpy_polyfit():
    T = RNG.uniform(-40, 60, 500)
    y = 0.3 + 0.03 * T + 6e-4 * T**2 + RNG.normal(size=T.size) * 0.1
    basis = make_basis(("T",), ((0,), (1,), (2,)), T)
    X = np.asarray(evaluate(np.eye(3), T[:, None], basis))
    coef, *_ = np.linalg.lstsq(X, y, rcond=None)
    doc = coefficient_document(basis, coef, np.eye(3) * 1e-4)
    # numpy's own least-squares fit in raw powers of T is the independent reference
    np.testing.assert_allclose(doc["raw"]["coef"], np.polynomial.polynomial.polyfit(T, y, 2),
                               rtol=1e-8)
    assert basis_from_dict(basis_to_dict(basis)) == basis
    assert doc["raw"]["terms"] == ["1", "T", "T^2"]


def _px4_offset(params, axis, T):
    """PX4's formula, written out independently (rad/s): clamp, subtract TREF, cubic."""
    g = "TC_G0_"
    dT = np.clip(T, params[g + "TMIN"], params[g + "TMAX"]) - params[g + "TREF"]
    return sum(params[f"{g}X{k}_{axis}"] * dT**k for k in range(4))


def test_px4_parameters_reproduce_the_model_in_rad_s():
    T, basis, coef = _cubic(200)
    axes = [(basis, coef), (basis, 0.5 * coef), (basis, -coef)]
    params = px4_gyro_parameters(axes, device_id=2490378)
    assert params["TC_G0_TREF"] == pytest.approx(20.0) and params["TC_G0_ID"] == 2490378
    assert (params["TC_G0_TMIN"], params["TC_G0_TMAX"]) == pytest.approx((-20.0, 60.0))
    for a, (b, c) in enumerate(axes):
        model = np.asarray(evaluate(c, T[:, None], b)) * DEG_H_TO_RAD_S
        np.testing.assert_allclose(_px4_offset(params, a, T), model, rtol=1e-9)
    # outside the calibrated range PX4 clamps: the offset is held at the edge
    assert _px4_offset(params, 0, np.array([80.0])) == pytest.approx(_px4_offset(params, 0, np.array([60.0])))
    text = px4_param_file(params)
    assert "1\t1\tTC_G0_X3_2\t" in text and "\t9\n" in text and "TC_G0_ID\t2490378\t6" in text


def test_px4_refuses_models_firmware_cannot_run():
    z = np.column_stack([np.linspace(0, 40, 50), np.linspace(-1, 1, 50)])
    thermal = thermal_basis(ThermalSpec(2, 1), z)
    with pytest.raises(ExportError, match="cubic in temperature only"):
        px4_gyro_parameters([(thermal, np.zeros(thermal.n_terms))])
    quartic = thermal_basis(bias_t_spec(4), z[:, :1])
    with pytest.raises(ExportError):
        px4_gyro_parameters([(quartic, np.zeros(5))])
