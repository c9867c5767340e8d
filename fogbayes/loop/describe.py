"""Physical description of an added term: the numbers a user reads in ``steps[].detail``.

Coefficients are fitted on centred/scaled columns (:mod:`fogbayes.diagnose.terms`); here
they are turned back into physical units (deg/h and the covariate's own unit).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..diagnose.terms import Term, labels


def _coef(beta: np.ndarray, se: np.ndarray, factor: float = 1.0) -> dict[str, float]:
    return {"value": float(beta * factor), "stderr": float(se * abs(factor))}


def describe(term: Term, beta: np.ndarray, se: np.ndarray, *, t0: float) -> dict[str, Any]:
    """``detail`` of a step: term kind, searched value, physical coefficients (+- 1 s.e.)."""
    k, p = term.kind, term.params
    d: dict[str, Any] = {"term": k}
    if k == "step":
        d.update(time_s=p["time"] + t0, time_from_start_s=p["time"], size_deg_h=_coef(beta[0], se[0]))
    elif k == "periodic":
        a, b = float(beta[0]), float(beta[1])
        amp = math.hypot(a, b)
        d.update(frequency_hz=p["frequency"], period_s=1.0 / p["frequency"],
                 amplitude_deg_h={"value": amp, "stderr": float(np.sqrt(np.mean(se ** 2)))},
                 phase_rad=math.atan2(b, a))
    elif k == "lag":
        d.update(tau_s=p["tau"], channel=p["channel"],
                 coefficient_deg_h_per_degC=_coef(beta[0], se[0], 1.0 / p["scale"]))
    elif k == "drift_exp":
        d.update(form="warm-up A (1 - exp(-t / tau))", tau_s=p["tau"],
                 amplitude_deg_h=_coef(beta[0], se[0], -1.0))
    elif k == "drift_lin":
        d.update(form="linear", slope_deg_h_per_h=_coef(beta[0], se[0], 3600.0 / p["duration"]))
    elif k == "rate":
        d.update(coefficient_deg_h_per_degC_per_min=_coef(beta[0], se[0], 1.0 / p["scale"]))
    elif k == "gradient":
        d.update(channels=[p["a"], p["b"]],
                 coefficient_deg_h_per_degC=_coef(beta[0], se[0], 1.0 / p["scale"]))
    elif k == "hysteresis":
        d.update(r0_degC_per_min=p["r0"], form="(h/2) tanh(dT/dt / r0)",
                 heating_minus_cooling_deg_h=_coef(beta[0], se[0], 2.0))
    else:
        d["coefficients_scaled"] = {lab: _coef(b, s) for lab, b, s in zip(labels(term), beta, se)}
        d["scaling"] = {key: v for key, v in p.items() if key != "effect"}
    return d
