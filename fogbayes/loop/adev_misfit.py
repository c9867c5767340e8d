"""ADEV misfit: the ``allan`` base model's residual, before and after each added noise term.

AVAR_model(tau) = sum_{n=-2..2} a_n tau^n + sum_added AVAR_term(tau), a_n >= 0 by NNLS, the
added terms fixed (paper 002 table 1). Misfit: RMS of (log ADEV_emp - log ADEV_model) in
standard errors (log-interval half-width / 1.645; ~1 when adequate) over tau >= ``tau_min``;
``rms_dex`` the plain RMS of log10(ADEV_emp / ADEV_model).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from scipy.optimize import nnls

from ..allan.model import markov_avar, sinusoid_avar
from ..effects.kinds import Periodic
from ..stats.allan import allan_deviation


class AdevMisfit(NamedTuple):
    misfit: float
    rms_dex: float
    tau: np.ndarray
    adev: np.ndarray
    adev_model: np.ndarray


def _extra_avar(tau: np.ndarray, details) -> np.ndarray:
    out = np.zeros_like(tau)
    for d in details:
        if d.get("term") == "gauss_markov_noise":
            out += np.asarray(markov_avar(tau, sigma=d["sigma_deg_h"], tau_c=d["tau_c_s"]))
        elif d.get("term") == Periodic.name:
            out += np.asarray(sinusoid_avar(tau, amplitude=d["amplitude_deg_h"]["value"],
                                            frequency=d["frequency_hz"]))
    return out


def adev_misfit(rate: np.ndarray, fs: float, details=(), *,
                tau_min: float = 0.0) -> AdevMisfit | None:
    """Misfit of five-term + the terms ``details`` describe (Gauss-Markov components,
    periodic steps' details) to the ADEV of ``rate`` (None if too short)."""
    try:
        a = allan_deviation(np.asarray(rate, float), fs, taus="octave")
    except ValueError:
        return None
    tau, var = np.asarray(a.tau), np.asarray(a.var)
    ok = (np.isfinite(var) & (var > 0) & (np.asarray(a.dev_high) > np.asarray(a.dev_low))
          & (tau >= tau_min))
    if ok.sum() < 6:
        return None
    tau, var = tau[ok], var[ok]
    lo, hi = np.asarray(a.dev_low)[ok], np.asarray(a.dev_high)[ok]
    extra = _extra_avar(tau, details)
    A = np.column_stack([tau ** n for n in (-2, -1, 0, 1, 2)]) / var[:, None]
    coef, _ = nnls(A, np.maximum(var - extra, 0.0) / var)
    model = np.column_stack([tau ** n for n in (-2, -1, 0, 1, 2)]) @ coef + extra
    dev, dev_m = np.sqrt(var), np.sqrt(np.maximum(model, 1e-300))
    se = 0.5 * (np.log(hi) - np.log(lo)) / 1.645
    z = (np.log(dev) - np.log(dev_m)) / se
    dex = np.log10(dev / dev_m)
    return AdevMisfit(float(np.sqrt(np.mean(z * z))), float(np.sqrt(np.mean(dex * dex))),
                      tau, dev, dev_m)
