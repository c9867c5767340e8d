"""One definition per term kind: columns, labels, physical description, sensor or run.

Every :class:`~fogbayes.effects.terms.Term` (``kind`` + ``params``) behaves as the :class:`Kind`
registered under ``kind``; columns are scaled to O(1), coefficients in deg/h. Kinds: intercept,
tpoly, rate, rate_poly, t_rate, gradient, hysteresis (tanh(dT/dt / r0)), play, lag (tau dL/dt =
T - L), drift_lin, drift_exp, periodic, step, omega_poly, omega_abs, omega_tpoly, drift_tpoly.
``applies``: ``"sensor"`` (carried by a calibration) or ``"run"`` (an event of one run).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from .lag import first_order_lag
from .play import play


def _channel(cov, name) -> np.ndarray:
    if isinstance(name, (int, np.integer)):
        return cov.T[:, int(name)]
    return cov.T[:, cov.names.index(name)]


def _z(cov, p) -> np.ndarray:
    return (_channel(cov, p["channel"]) - p["centre"]) / p["scale"]


#: axis label of the drivers with a fixed unit
DRIVER_LABELS = {"dT/dt": "dT/dt [°C/min]", "time": "time [h]", "input_rate": "input rate [°/s]"}


def _coef(beta, se, factor: float = 1.0) -> dict[str, float]:
    return {"value": float(beta * factor), "stderr": float(se * abs(factor))}


class Kind:
    """A term kind: subclasses set ``name`` and override :meth:`columns` (and what differs)."""

    name: str = ""
    applies: str = "sensor"
    powered: bool = False  # one column per entry of params["powers"]
    #: parameters the columns need: "pos" positive number (a divisor), "num" finite
    #: number, "int" temperature-channel index, "powers" list of exponents
    needs: dict[str, str] = {}
    #: the searched scale that refine.polish re-scores after the decision, if any
    scale_key: str | None = None
    #: the physical variable the column follows (plot axis): "dT/dt", "time", "input_rate",
    #: "channel" (params["channel"]), "gradient", "phase" or None (the column itself)
    driver: str | None = None

    @property
    def driver_label(self) -> str | None:
        return DRIVER_LABELS.get(self.driver)

    @property
    def time_driven(self) -> bool:
        return self.driver == "time"

    def n_cols(self, p: dict) -> int:
        return len(p["powers"]) if self.powered else 1

    def columns(self, p: dict, cov) -> np.ndarray:
        raise NotImplementedError

    def chunk_columns(self, p: dict, cov, state):
        """Columns of one chunk of a record read in order, and the state the next chunk
        needs (``state`` None on the first chunk). Equal to :meth:`columns` of the whole
        record cut into pieces; only kinds with memory (a filter of the past) override it."""
        return self.columns(p, cov), None

    def labels(self, p: dict) -> list[str]:
        return [self.name]

    def rate_powers(self, p: dict) -> list[tuple[int, bool]]:
        """Per column, how it depends on the input rate W: (m, absolute) for a column equal
        to its value at W = ``p["scale"]`` times (W / scale)^m, or |W / scale|^m when
        ``absolute``; m = 0 for a column that does not depend on W. The composite family
        inverts its model through this (:mod:`fogbayes.loop.compensate`)."""
        return [(0, False)] * self.n_cols(p)

    def describe(self, p: dict, beta, se, t0: float) -> dict[str, Any]:
        """Physical reading of the fitted coefficients (deg/h and the driver's own unit)."""
        return {"coefficients_scaled": {lab: _coef(b, s) for lab, b, s in
                                        zip(self.labels(p), beta, se)},
                "scaling": {k: v for k, v in p.items() if k != "effect"}}


class Intercept(Kind):
    name = "intercept"
    needs = {}

    def columns(self, p, cov):
        return np.ones((cov.t.size, 1))


class TPoly(Kind):
    name, powered, driver = "tpoly", True, "channel"
    needs = {"channel": "int", "powers": "powers", "centre": "num", "scale": "pos"}

    def columns(self, p, cov):
        z = _z(cov, p)
        return np.column_stack([z ** e for e in p["powers"]])

    def labels(self, p):
        return [f"T'^{e}" for e in p["powers"]]


class Rate(Kind):
    name, driver = "rate", "dT/dt"
    needs = {"scale": "pos"}

    def columns(self, p, cov):
        return (cov.Tdot / p["scale"])[:, None]

    def describe(self, p, beta, se, t0):
        return {"coefficient_deg_h_per_degC_per_min": _coef(beta[0], se[0], 1.0 / p["scale"])}


class RatePoly(Kind):
    name, powered, driver = "rate_poly", True, "dT/dt"
    needs = {"powers": "powers", "scale": "pos"}

    def columns(self, p, cov):
        z = cov.Tdot / p["scale"]
        return np.column_stack([z ** e for e in p["powers"]])

    def labels(self, p):
        return [f"(dT/dt)'^{e}" for e in p["powers"]]


class TRate(Kind):
    name = "t_rate"
    needs = {"channel": "int", "centre": "num", "scale": "pos", "rate_scale": "pos"}

    def columns(self, p, cov):
        return (_z(cov, p) * cov.Tdot / p["rate_scale"])[:, None]

    def labels(self, p):
        return ["T' (dT/dt)'"]


class Gradient(Kind):
    name, driver = "gradient", "gradient"
    needs = {"a": "int", "b": "int", "scale": "pos"}

    def columns(self, p, cov):
        return ((_channel(cov, p["b"]) - _channel(cov, p["a"])) / p["scale"])[:, None]

    def describe(self, p, beta, se, t0):
        return {"channels": [p["a"], p["b"]],
                "coefficient_deg_h_per_degC": _coef(beta[0], se[0], 1.0 / p["scale"])}


class Hysteresis(Kind):
    name, driver, scale_key = "hysteresis", "dT/dt", "r0"
    needs = {"r0": "pos"}

    def columns(self, p, cov):
        return np.tanh(cov.Tdot / p["r0"])[:, None]

    def describe(self, p, beta, se, t0):
        return {"r0_degC_per_min": p["r0"], "form": "(h/2) tanh(dT/dt / r0)",
                "heating_minus_cooling_deg_h": _coef(beta[0], se[0], 2.0)}


class Play(Kind):
    name, driver, scale_key = "play", "channel", "width"
    needs = {"channel": "int", "width": "pos"}

    def columns(self, p, cov):
        return self.chunk_columns(p, cov, None)[0]

    def chunk_columns(self, p, cov, state):
        T = _channel(cov, p["channel"])
        P = play(T, p["width"], initial=state)
        return ((T - P) / (0.5 * p["width"]))[:, None], float(P[-1])

    def describe(self, p, beta, se, t0):
        return {"width_degC": p["width"], "channel": p["channel"],
                "form": "(h/2) (T - P_w[T]) / (w/2), P_w the play operator of width w",
                "heating_minus_cooling_deg_h": _coef(beta[0], se[0], 2.0)}


class Lag(Kind):
    name, driver, scale_key = "lag", "channel", "tau"
    needs = {"channel": "int", "tau": "pos", "centre": "num", "scale": "pos"}

    def columns(self, p, cov):
        return self.chunk_columns(p, cov, None)[0]

    def chunk_columns(self, p, cov, state):
        t, u = cov.t, _channel(cov, p["channel"])
        if state is None:
            L = first_order_lag(t, u, p["tau"])
        else:  # the previous chunk's last sample starts the recursion
            t_prev, u_prev, L_prev = state
            L = first_order_lag(np.concatenate([[t_prev], t]), np.concatenate([[u_prev], u]),
                                p["tau"], initial=L_prev)[1:]
        return ((L - p["centre"]) / p["scale"])[:, None], (float(t[-1]), float(u[-1]),
                                                          float(L[-1]))

    def describe(self, p, beta, se, t0):
        return {"tau_s": p["tau"], "channel": p["channel"],
                "coefficient_deg_h_per_degC": _coef(beta[0], se[0], 1.0 / p["scale"])}


class DriftLin(Kind):
    name, applies, driver = "drift_lin", "run", "time"
    needs = {"duration": "pos"}

    def columns(self, p, cov):
        return (cov.t / p["duration"])[:, None]

    def describe(self, p, beta, se, t0):
        return {"form": "linear",
                "slope_deg_h_per_h": _coef(beta[0], se[0], 3600.0 / p["duration"])}


class DriftExp(Kind):
    name = "drift_exp"  # a warm-up since power-on (the first sample): a sensor property
    driver, scale_key = "time", "tau"
    needs = {"tau": "pos"}

    def columns(self, p, cov):
        return np.exp(-cov.t / p["tau"])[:, None]

    def describe(self, p, beta, se, t0):
        return {"form": "warm-up A (1 - exp(-t / tau))", "tau_s": p["tau"],
                "amplitude_deg_h": _coef(beta[0], se[0], -1.0)}


class Periodic(Kind):
    name, applies, driver = "periodic", "run", "phase"
    needs = {"frequency": "pos"}

    def n_cols(self, p):
        return 2

    def columns(self, p, cov):
        ph = 2.0 * np.pi * p["frequency"] * cov.t
        return np.column_stack([np.sin(ph), np.cos(ph)])

    def labels(self, p):
        return ["sin", "cos"]

    def describe(self, p, beta, se, t0):
        a, b = float(beta[0]), float(beta[1])
        return {"frequency_hz": p["frequency"], "period_s": 1.0 / p["frequency"],
                "amplitude_deg_h": {"value": math.hypot(a, b),
                                    "stderr": float(np.sqrt(np.mean(np.asarray(se) ** 2)))},
                "phase_rad": math.atan2(b, a)}


class Step(Kind):
    name, applies, driver = "step", "run", "time"
    needs = {"time": "num"}

    def columns(self, p, cov):
        return (cov.t >= p["time"]).astype(float)[:, None]

    def describe(self, p, beta, se, t0):
        return {"time_s": p["time"] + t0, "time_from_start_s": p["time"],
                "size_deg_h": _coef(beta[0], se[0])}


class OmegaPoly(Kind):
    name, powered, driver = "omega_poly", True, "input_rate"
    needs = {"powers": "powers", "scale": "pos"}

    def columns(self, p, cov):
        z = cov.omega / p["scale"]
        return np.column_stack([z ** e for e in p["powers"]])

    def labels(self, p):
        return [f"W'^{e}" for e in p["powers"]]

    def rate_powers(self, p):
        return [(int(e), False) for e in p["powers"]]


class OmegaAbs(Kind):
    name, driver = "omega_abs", "input_rate"
    needs = {"scale": "pos"}

    def columns(self, p, cov):
        return (np.abs(cov.omega) / p["scale"])[:, None]

    def rate_powers(self, p):
        return [(1, True)]


class OmegaTPoly(Kind):
    name, powered, driver = "omega_tpoly", True, "input_rate"
    needs = {"channel": "int", "powers": "powers", "centre": "num", "t_scale": "pos",
             "scale": "pos"}

    def columns(self, p, cov):
        z = (_channel(cov, p["channel"]) - p["centre"]) / p["t_scale"]
        wz = (cov.omega / p["scale"]) ** p.get("wpower", 1)
        return np.column_stack([wz * z ** e for e in p["powers"]])

    def labels(self, p):
        return [f"W' T'^{e}" for e in p["powers"]]

    def rate_powers(self, p):
        return [(int(p.get("wpower", 1)), False)] * len(p["powers"])


class DriftTPoly(Kind):
    name, powered, driver = "drift_tpoly", True, "time"
    needs = {"channel": "int", "powers": "powers", "centre": "num", "scale": "pos",
             "duration": "pos"}

    def columns(self, p, cov):  # U1(T) t with t the operating time when the run has one
        tt = cov.op_time if cov.op_time is not None else cov.t
        z = _z(cov, p)
        return np.column_stack([tt / p["duration"] * z ** e for e in p["powers"]])

    def labels(self, p):
        return [f"t' T'^{e}" for e in p["powers"]]


KINDS: dict[str, Kind] = {k.name: k() for k in (
    Intercept, TPoly, Rate, RatePoly, TRate, Gradient, Hysteresis, Play, Lag, DriftLin, DriftExp, Periodic,
    Step, OmegaPoly, OmegaAbs, OmegaTPoly, DriftTPoly)}


def kind_of(name: str) -> Kind:
    """The :class:`Kind` registered as ``name`` (ValueError naming it otherwise)."""
    try:
        return KINDS[name]
    except KeyError:
        raise ValueError(f"unknown term kind {name!r}") from None
