"""Effects by name: covariates needed, default parameters, one-line help.

``effect_rate(name, cov, params)`` in deg/h from :class:`~fogbayes.simulate.truth.Covariates`;
``EffectSpec.terms(params)`` plants each through the loop's term kinds
(:mod:`fogbayes.diagnose.kinds`); closed forms in :mod:`fogbayes.simulate.effects` are the
independent reference. ``markov_noise`` is drawn by the scenario.
"""

from __future__ import annotations

from typing import Any, Callable, NamedTuple

import numpy as np

from ..diagnose.covariates import Covariates as TermCovariates
from ..diagnose.terms import Term, design
from ._checks import SimulationParameterError
from .truth import Covariates

Planted = list[tuple[Term, list[float]]]


class EffectSpec(NamedTuple):
    fn: Callable[[Covariates, dict], np.ndarray] | None  # None: stochastic (markov_noise)
    defaults: dict[str, Any]
    description: str
    terms: Callable[[dict], Planted] | None = None  # the effect as loop terms (module doc)


def term_covariates(c: Covariates) -> TermCovariates:
    """The simulator's true covariates as the loop's term covariates (same clock)."""
    names = tuple(f"T{j + 1}" for j in range(c.temperatures.shape[1]))
    return TermCovariates(np.asarray(c.time, float), np.asarray(c.temperatures, float), names,
                          np.asarray(c.dTdt, float), c.input_rate,
                          float(c.time[-1] - c.time[0]), c.operating_time)


def _planted(terms: Callable[[dict], Planted],
             check=None) -> Callable[[Covariates, dict], np.ndarray]:
    """An effect's rate from its terms: sum_j X_j(cov) c_j (deg/h)."""
    def fn(c: Covariates, p: dict) -> np.ndarray:
        if check is not None:
            check(c)
        pairs = terms(p)
        X = design([t for t, _ in pairs], term_covariates(c))
        return X @ np.concatenate([np.asarray(k, float) for _, k in pairs])
    return fn


def _effect(terms: Callable[[dict], Planted], defaults: dict, description: str,
            check=None) -> EffectSpec:
    return EffectSpec(_planted(terms, check), defaults, description, terms)


def _periodic(p: dict) -> Planted:
    a, ph = p["amplitude"], p["phase"]  # A sin(wt + ph) = A cos(ph) sin(wt) + A sin(ph) cos(wt)
    return [(Term("periodic", {"frequency": p["frequency"]}),
             [a * np.cos(ph), a * np.sin(ph)])]


def _hysteresis(p: dict) -> Planted:  # rate-type (tanh) or, given a width, memory (play)
    if p.get("width") is not None:
        return [(Term("play", {"channel": 0, "width": p["width"]}), [0.5 * p["size"]])]
    return [(Term("hysteresis", {"r0": p["rate_scale"]}), [0.5 * p["size"]])]


def _drift(p: dict) -> Planted:  # s t / 3600 + A (1 - exp(-t / tau))
    return [(Term("drift_lin", {"duration": 3600.0}), [p["slope"]]),
            (Term("intercept", {}), [p["amplitude"]]),
            (Term("drift_exp", {"tau": p["tau"]}), [-p["amplitude"]])]


def _paper004(p: dict) -> Planted:  # c0 + c1 x + c2 x^2 + d1 r + d2 r^2 + e x r
    x = {"channel": 0, "centre": p["T_ref"], "scale": 1.0}
    return [(Term("tpoly", {**x, "powers": list(range(len(p["c"])))}), list(p["c"])),
            (Term("rate_poly", {"powers": list(range(1, len(p["d"]) + 1)), "scale": 1.0}),
             list(p["d"])),
            (Term("t_rate", {**x, "rate_scale": 1.0}), [p["cross"]])]


def _omega(cov: Covariates, name: str) -> np.ndarray:
    if cov.input_rate is None:
        raise SimulationParameterError(
            f"effect '{name}' acts on the input rate but this scenario has none",
            column=name, fix="use the 'ratetable' or 'paper000' scenario, or pass input_rate=")
    return cov.input_rate


def _second(cov: Covariates, name: str) -> np.ndarray:
    if cov.temperatures.shape[1] < 2:
        raise SimulationParameterError(
            f"effect '{name}' needs two temperature channels, this scenario has "
            f"{cov.temperatures.shape[1]}", column=name, fix="use a scenario with two channels")
    return cov.temperatures[:, 1]


EFFECTS: dict[str, EffectSpec] = {
    "temperature_order": _effect(
        lambda p: [(Term("tpoly", {"channel": 0, "powers": list(range(len(p["coeffs"]))),
                                   "centre": p["T_ref"], "scale": 1.0}), list(p["coeffs"]))],
        {"coeffs": [0.0, 0.0, 0.0, 2e-6], "T_ref": 20.0},
        "bias polynomial in temperature, sum_i c_i (T - T_ref)^i (deg/h)"),
    "temperature_rate": _effect(
        lambda p: [(Term("rate", {"scale": 1.0}), [p["coeff"]])], {"coeff": 0.3},
        "Shupe term k dT/dt (deg/h per deg C/min)"),
    "temperature_gradient": _effect(
        lambda p: [(Term("gradient", {"a": 0, "b": 1, "scale": 1.0}), [p["coeff"]])],
        {"coeff": 0.03}, "k (T2 - T1) between the two channels (deg/h per deg C)",
        check=lambda c: _second(c, "temperature_gradient")),
    "thermal_hysteresis": _effect(
        _hysteresis, {"size": 0.2, "rate_scale": 0.05, "width": None},
        "(h/2) tanh(dT/dt / r0): bias h higher heating than cooling (deg/h); with width w "
        "(deg C) the memory form (h/2) (T - P_w[T]) / (w/2), P_w the play operator"),
    "thermal_lag": _effect(
        lambda p: [(Term("lag", {"channel": 0, "tau": p["tau"], "centre": p["T_ref"],
                                 "scale": 1.0}), [p["coeff"]])],
        {"coeff": 0.01, "tau": 1800.0, "T_ref": 20.0},
        "k (T_lag - T_ref), T_lag = T through a first-order lag tau (s)"),
    "time_drift": _effect(
        _drift, {"slope": 0.0, "amplitude": 1.0, "tau": 5400.0},
        "s t/3600 + A (1 - exp(-t/tau)): drift and warm-up (deg/h)"),
    "periodic": _effect(
        _periodic, {"amplitude": 0.1, "frequency": 1.0 / 600.0, "phase": 0.0},
        "A sin(2 pi f t + phase) (deg/h, Hz)"),
    "step": _effect(
        lambda p: [(Term("step", {"time": p["time"]}), [p["size"]])], {"time": None, "size": 0.2},
        "bias step of `size` deg/h at `time` s (default: mid-record)"),
    "scale_factor_nonlinearity": _effect(
        lambda p: [(Term("omega_poly", {"powers": [2, 3], "scale": 1.0}),
                    [3600.0 * p["k2"], 3600.0 * p["k3"]])],
        {"k2": 1e-6, "k3": 1e-8}, "3600 (k2 w^2 + k3 w^3) deg/h, w in deg/s",
        check=lambda c: _omega(c, "scale_factor_nonlinearity")),
    "scale_factor_asymmetry": _effect(
        lambda p: [(Term("omega_abs", {"scale": 1.0}), [1800.0 * p["asymmetry"]])],
        {"asymmetry": 1e-4}, "1800 a |w| deg/h: scale (1 +- a/2) for w > 0 / w < 0",
        check=lambda c: _omega(c, "scale_factor_asymmetry")),
    "scale_factor_temperature": _effect(
        lambda p: [(Term("omega_tpoly", {"channel": 0, "powers": [1], "centre": p["T_ref"],
                                         "t_scale": 1.0, "scale": 1.0}),
                    [3600.0 * p["coeff"]])],
        {"coeff": 1e-6, "T_ref": 20.0}, "3600 w k (T - T_ref) deg/h: scale linear in T",
        check=lambda c: _omega(c, "scale_factor_temperature")),
    "markov_noise": EffectSpec(
        None, {"sigma": 0.05, "tau_c": 300.0},
        "first-order Gauss-Markov noise, std sigma deg/h, correlation time tau_c s"),
    "paper004": _effect(
        _paper004, {"c": [0.0, 0.0, 0.0], "d": [0.0, 0.0], "cross": 0.0, "T_ref": 0.0},
        "paper 004 bias: order-2 polynomial in T and dT/dt (+ cross term) (deg/h)"),
}


def _number(v) -> bool:
    return isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, bool) \
        and bool(np.isfinite(v))


def resolve(name: str, params: dict | None, cov: Covariates) -> dict[str, Any]:
    """The effect's full parameter set: defaults updated by ``params``; unknown keys raise."""
    if name not in EFFECTS:
        raise SimulationParameterError(f"unknown effect '{name}'", argument="effects",
                                       fix=f"use one of {', '.join(sorted(EFFECTS))}")
    spec = EFFECTS[name]
    params = dict(params or {})
    bad = set(params) - set(spec.defaults)
    if bad:
        raise SimulationParameterError(
            f"effect '{name}' has no parameter(s) {sorted(bad)}", column=name,
            fix=f"use {sorted(spec.defaults)}")
    for key, value in params.items():  # numbers where the default is a number or a list
        want = spec.defaults[key]
        listed = isinstance(want, (list, tuple))
        if listed:
            ok = isinstance(value, (list, tuple, np.ndarray)) and \
                all(_number(v) for v in np.ravel(np.asarray(value, dtype=object)))
        else:
            ok = _number(value) or (want is None and value is None)
        if not ok:
            what = "a list of numbers" if listed else "a finite number"
            raise SimulationParameterError(f"effect '{name}': {key}={value!r} is not {what}",
                                           column=name, fix=f"give e.g. {key}={want!r}")
    full = {**spec.defaults, **params}
    if name == "step" and full["time"] is None:
        full["time"] = float(cov.time[0] + 0.5 * (cov.time[-1] - cov.time[0]))
    return full


def on_top(name: str, own: dict, cov: Covariates) -> dict[str, Any]:
    """Parameters of effect ``name`` at its registry default *added to* the scenario's ``own``.

    Naming an effect that the scenario's model already has, without parameters, must plant
    something the declared model lacks -- ``fogbayes simulate thermal --effect
    temperature_order`` is otherwise the clean scenario. For ``temperature_order`` the
    polynomials add, coefficient by coefficient (same ``T_ref``)::

        sum_i (a_i + c_i) (T - T_ref)^i     a: the scenario's, c: the registry default

    Other effects have no meaningful sum; they keep the scenario's parameters.
    """
    mine = resolve(name, own, cov)
    if name != "temperature_order":
        return mine
    extra = resolve(name, None, cov)
    if extra["T_ref"] != mine["T_ref"]:
        raise SimulationParameterError(
            "temperature_order on top of the scenario's needs the same T_ref",
            column=name, fix=f"give the full coefficients with T_ref {mine['T_ref']}")
    a, c = list(mine["coeffs"]), list(extra["coeffs"])
    n = max(len(a), len(c))
    a, c = a + [0.0] * (n - len(a)), c + [0.0] * (n - len(c))
    return {**mine, "coeffs": [float(x + y) for x, y in zip(a, c)]}


def effect_rate(name: str, cov: Covariates, params: dict) -> np.ndarray:
    """Deterministic effect ``name`` in deg/h with the full parameters ``params``."""
    return np.broadcast_to(EFFECTS[name].fn(cov, params), cov.time.shape).astype(float)
