"""Coefficient export: a JSON document per model, and PX4 / ArduPilot thermal-compensation parameters.

JSON (:mod:`fogbayes.models.basis_document`): scaled-basis coefficients, covariance, raw
coefficients with standard errors. PX4 (``TC_G<i>_*``, rad/s): offset = sum_k X<k> dT^k,
dT = clamp(T) - TREF
(:func:`px4_gyro_parameters`, bias-t order <= 3; loop documents via :func:`basis_from_loop`).
ArduPilot (``INS_TCAL<i>_*``): rate = raw - P(T - 35) + P(T_cal - 35), P(d) = (c1 d + c2 d^2 + c3 d^3) 1e-6
(:func:`ardupilot_gyro_parameters`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from ..errors import FogbayesError
from ..models.polynomial import PolyBasis, rebase_matrix

DEG_H_TO_RAD_S = math.pi / 180.0 / 3600.0


class ExportError(FogbayesError):
    """The model cannot be written in the requested format."""


def px4_gyro_parameters(axes: Sequence[tuple[PolyBasis, np.ndarray]], *, gyro_index: int = 0,
                        device_id: int = 0, t_ref: float | None = None,
                        t_range: tuple[float, float] | None = None) -> dict:
    """PX4 ``TC_G<i>_*`` parameters from one ``bias-t`` model (deg/h) per axis (x, y, z).

    ``t_ref`` defaults to the middle of ``t_range``, which defaults to the temperature span
    the fits were made on (the bases' ``centre +- scale``): outside it PX4 clamps.
    """
    if not 1 <= len(axes) <= 3:
        raise ExportError(f"PX4 takes 1 to 3 gyro axes, got {len(axes)}",
                          fix="pass the x, y, z fits in that order")
    _cubic_in_t(axes, "PX4")
    t_range = _span(axes) if t_range is None else t_range
    t_ref = 0.5 * (t_range[0] + t_range[1]) if t_ref is None else float(t_ref)
    g = f"TC_G{gyro_index}_"
    out: dict = {"TC_G_ENABLE": 1, g + "ID": int(device_id), g + "TREF": t_ref,
                 g + "TMIN": float(t_range[0]), g + "TMAX": float(t_range[1])}
    for a, (basis, coef) in enumerate(axes):
        about_ref = rebase_matrix(basis, origin=[t_ref]) @ np.asarray(coef, dtype=float)
        for k in range(4):
            v = about_ref[basis.terms.index((k,))] if (k,) in basis.terms else 0.0
            out[f"{g}X{k}_{a}"] = float(v * DEG_H_TO_RAD_S)
    return out


#: ArduPilot's fixed reference temperature (TEMP_REFERENCE) and parameter scale (SCALE_FACTOR)
ARDUPILOT_TREF = 35.0
ARDUPILOT_SCALE = 1.0e6


def _cubic_in_t(axes, firmware: str) -> None:
    for a, (basis, _) in enumerate(axes):
        if basis.names != ("T",) or max(e[0] for e in basis.terms) > 3:
            raise ExportError(
                f"axis {a}: {firmware} compensates with a cubic in temperature only, the model "
                f"has terms {basis.labels()}", column="model",
                fix=f"fit '--model bias-t --order 3' (or lower) for {firmware} export")


def _span(axes) -> tuple[float, float]:
    return (min(b.centre[0] - b.scale[0] for b, _ in axes),
            max(b.centre[0] + b.scale[0] for b, _ in axes))


def ardupilot_gyro_parameters(axes: Sequence[tuple[PolyBasis, np.ndarray]], *, imu_index: int = 1,
                              t_range: tuple[float, float] | None = None) -> dict:
    """ArduPilot ``INS_TCAL<i>_*`` gyro parameters from one ``bias-t`` model (deg/h) per axis.

    ``GYR<k>_<X|Y|Z>`` = 1e6 x the degree-k coefficient (rad/s) of the bias about 35 degC;
    ``TMIN``/``TMAX`` default to the temperature span the fits were made on (outside it the
    firmware clamps). The accelerometer parameters (``ACC<k>_*``) are not written: loading
    the file leaves an existing accelerometer calibration as it is.
    """
    if not 1 <= len(axes) <= 3:
        raise ExportError(f"ArduPilot takes 1 to 3 gyro axes, got {len(axes)}",
                          fix="pass the x, y, z fits in that order")
    _cubic_in_t(axes, "ArduPilot")
    lo, hi = _span(axes) if t_range is None else t_range
    p = f"INS_TCAL{int(imu_index)}_"
    out: dict = {p + "ENABLE": 1, p + "TMIN": float(lo), p + "TMAX": float(hi)}
    for a, (basis, coef) in enumerate(axes):
        about_ref = rebase_matrix(basis, origin=[ARDUPILOT_TREF]) @ np.asarray(coef, dtype=float)
        for k in (1, 2, 3):
            v = about_ref[basis.terms.index((k,))] if (k,) in basis.terms else 0.0
            out[f"{p}GYR{k}_{'XYZ'[a]}"] = float(v * DEG_H_TO_RAD_S * ARDUPILOT_SCALE)
    return out


def ardupilot_param_file(params: dict) -> str:
    """Mission Planner / MAVProxy ``.param`` text: ``NAME,VALUE`` lines."""
    lines = ["# ArduPilot gyro temperature calibration written by fogbayes export",
             "# the accelerometer INS_TCAL*_ACC* parameters are not included",
             "# valid only if the log was recorded with INS_TCAL<i>_ENABLE = 0 (else its rates",
             "# were already corrected) and its axes are the sensor's (AHRS_ORIENTATION = 0;",
             "# the logged IMU rates are rotated by the board orientation, the correction is not)"]
    lines += [f"{k},{v}" if isinstance(v, int) else f"{k},{v:.9g}" for k, v in params.items()]
    return "\n".join(lines) + "\n"


def basis_from_loop(doc: dict, *, source: str | None = None) -> tuple[PolyBasis, np.ndarray]:
    """The temperature polynomial of a loop document's calibration as (basis, coef), deg/h.

    The sensor's terms must be the intercept and powers of the first temperature channel
    (one centre and scale), the form PX4 takes; any other sensor term (dT/dt, a gradient, a
    lag, hysteresis, a warm-up, a scale factor) is refused by name. Run events of the
    calibration run (a step, a linear drift, a periodic term) are not part of the sensor
    and are left out.
    """
    from ..effects.kinds import kind_of  # the loop's term kinds (imported on use: numba)

    cal = doc["calibration"]
    powers, coef, where, i = [], [], None, 0
    for t in cal["terms"]:
        k = kind_of(t["kind"]).n_cols(t["params"])  # one rule of columns per kind
        c = cal["coefficients"][i:i + k]
        i += k
        if t.get("applies") == "run":
            continue
        if t["kind"] == "intercept":
            powers.append(0)
            coef.extend(c)
        elif t["kind"] == "tpoly" and t["params"]["channel"] == 0:
            p = t["params"]
            if where is not None and where != (p["centre"], p["scale"]):
                raise ExportError("the calibration's temperature terms use different "
                                  "centres/scales", file=source, field="calibration.terms")
            where = (p["centre"], p["scale"])
            powers.extend(p["powers"])
            coef.extend(c)
        else:
            raise ExportError(f"PX4 and ArduPilot compensate with a polynomial in one temperature; the "
                              f"calibration has the term {t['effect']!r} ({t['kind']}), which "
                              f"the firmware has no input for", file=source, field="model",
                              fix="export a loop run without that effect, or apply the "
                                  "calibration with 'fogbayes compensate'")
    centre, scale = where if where is not None else (0.0, 1.0)
    return (PolyBasis(("T",), tuple((e,) for e in powers), (float(centre),), (float(scale),)),
            np.asarray(coef, float))


def px4_param_file(params: dict, *, vehicle_id: int = 1, component_id: int = 1) -> str:
    """QGroundControl ``.params`` text: ``vehicle component NAME value type`` (9 = float, 6 = int)."""
    lines = ["# Onboard parameters for Vehicle 1", "#",
             "# Vehicle-Id Component-Id Name Value Type"]
    for name, value in params.items():
        kind = 6 if isinstance(value, int) else 9
        text = str(value) if kind == 6 else f"{value:.9g}"
        lines.append(f"{vehicle_id}\t{component_id}\t{name}\t{text}\t{kind}")
    return "\n".join(lines) + "\n"
