"""The simulator plants every loop effect through the loop's own term kinds; each planted
effect equals its closed form (fogbayes.simulate.effects, written separately) to rounding,
and every term kind's description, run/sensor class and parameter rules come from one place."""

from __future__ import annotations

import numpy as np
import pytest

from fogbayes.effects.kinds import KINDS
from fogbayes.effects.terms import Term, columns, describe, labels
from fogbayes.simulate import effects as fx
from fogbayes.simulate.registry import EFFECTS, resolve, term_covariates
from fogbayes.simulate.truth import Covariates


@pytest.fixture(scope="module")
def cov():
    t = np.arange(0.0, 7200.0, 0.5)
    T1 = 20.0 + 30.0 * np.sin(2 * np.pi * t / 5000.0)
    T2 = 20.0 + 28.0 * np.sin(2 * np.pi * (t - 300.0) / 5000.0)
    dTdt = 60.0 * np.gradient(T1, t)
    w = 50.0 * np.sin(2 * np.pi * t / 900.0)
    return Covariates(t, T1, np.column_stack([T1, T2]), dTdt, w, None, t % 600.0)


CLOSED = {  # name -> closed form of the effect at its full parameters
    "temperature_order": lambda c, p: fx.temperature_order(c.temperature, **p),
    "temperature_rate": lambda c, p: fx.temperature_rate(c.dTdt, **p),
    "temperature_gradient": lambda c, p: fx.temperature_gradient(c.temperature,
                                                                 c.temperatures[:, 1], **p),
    "thermal_hysteresis": lambda c, p: fx.thermal_hysteresis(c.dTdt, T=c.temperature, **p),
    "thermal_lag": lambda c, p: fx.thermal_lag(c.time, c.temperature, **p),
    "time_drift": lambda c, p: fx.time_drift(c.time, **p),
    "periodic": lambda c, p: fx.periodic(c.time, **p),
    "step": lambda c, p: fx.step(c.time, **p),
    "scale_factor_nonlinearity": lambda c, p: fx.scale_factor_nonlinearity(c.input_rate, **p),
    "scale_factor_asymmetry": lambda c, p: fx.scale_factor_asymmetry(c.input_rate, **p),
    "scale_factor_temperature": lambda c, p: fx.scale_factor_temperature(c.input_rate,
                                                                         c.temperature, **p),
    "paper004": lambda c, p: fx.paper004_bias(c.temperature, c.dTdt, **p),
}
#: non-default parameters, so that every coefficient path is exercised
PARAMS = {"time_drift": {"slope": 0.3, "amplitude": 0.8, "tau": 900.0},
          "periodic": {"amplitude": 0.2, "frequency": 1 / 300.0, "phase": 0.7},
          "temperature_order": {"coeffs": [0.5, 0.01, 2e-4, -3e-6], "T_ref": 15.0},
          "thermal_lag": {"coeff": 0.02, "tau": 700.0, "T_ref": 10.0},
          "paper004": {"c": [0.3, 0.03, 6e-4], "d": [4.0, -0.5], "cross": 0.02, "T_ref": 5.0}}


def test_every_loop_effect_is_planted_through_term_kinds():
    have = {n for n, s in EFFECTS.items() if s.terms is not None}
    assert have == set(CLOSED)  # markov_noise (stochastic) aside


@pytest.mark.parametrize("name", sorted(CLOSED))
def test_planted_effect_equals_its_closed_form(cov, name):
    p = resolve(name, PARAMS.get(name), cov)
    got = EFFECTS[name].fn(cov, p)
    want = CLOSED[name](cov, p)
    scale = max(float(np.max(np.abs(want))), 1e-12)
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-12 * scale)
    assert np.ptp(want) > 0  # the comparison is not between two constants


def test_kinds_describe_the_coefficients_they_were_planted_with(cov):
    """Fitting nothing: a planted coefficient read back through ``describe`` is the physical
    parameter (Shupe k, hysteresis h, lag k, warm-up A, step size, periodic amplitude)."""
    cases = {"temperature_rate": ("coefficient_deg_h_per_degC_per_min", "coeff"),
             "thermal_hysteresis": ("heating_minus_cooling_deg_h", "size"),
             "thermal_lag": ("coefficient_deg_h_per_degC", "coeff"),
             "step": ("size_deg_h", "size"),
             "periodic": ("amplitude_deg_h", "amplitude")}
    for name, (key, param) in cases.items():
        p = resolve(name, PARAMS.get(name), cov)
        term, coef = EFFECTS[name].terms(p)[0]
        d = describe(term, np.asarray(coef), np.zeros(len(coef)), t0=0.0)
        assert d[key]["value"] == pytest.approx(p[param], rel=1e-12), name
    tc = term_covariates(cov)
    for name, spec in EFFECTS.items():
        if spec.terms is None:
            continue
        for term, coef in spec.terms(resolve(name, PARAMS.get(name), cov)):
            assert columns(term, tc).shape == (tc.t.size, term.n_cols) == (tc.t.size, len(coef))
            assert len(labels(term)) == term.n_cols


def test_run_events_and_sensor_properties():
    assert {k for k, v in KINDS.items() if v.applies == "run"} == {"step", "drift_lin",
                                                                     "periodic"}
    assert Term("drift_exp", {"tau": 60.0}).applies == "sensor"  # warm-up since power-on
    with pytest.raises(ValueError, match="unknown term kind"):
        Term("cosmic_ray", {}).n_cols


def test_memory_hysteresis_equals_its_closed_form(cov):
    """The play-operator (memory) shape of thermal_hysteresis: compiled kind vs the closed
    form's plain loop; it holds its level through a soak, where tanh returns to zero."""
    p = resolve("thermal_hysteresis", {"size": 0.6, "width": 3.0}, cov)
    got = EFFECTS["thermal_hysteresis"].fn(cov, p)
    want = fx.thermal_hysteresis(cov.dTdt, T=cov.temperature, **p)
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-12)
    assert np.max(np.abs(want)) == pytest.approx(0.3, rel=1e-9)  # +-h/2 once saturated
    soak = np.abs(cov.dTdt) < 1e-9
    assert soak.any() and np.max(np.abs(want[soak])) > 0.25  # held through the soaks
