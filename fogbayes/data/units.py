"""Angular-rate units and conversions.

Rates ``deg/h``, ``deg/s``, ``rad/s`` convert exactly; raw outputs (``V``, ``Hz``, ...) with scale
factor K in raw units per deg/s: rate[deg/s] = output / K.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import UnitError

#: One unit of each rate unit, expressed in deg/h.
RATE_UNITS_IN_DEG_H = {
    "deg/h": 1.0,
    "deg/s": 3600.0,
    "rad/s": 3600.0 * 180.0 / math.pi,
    "rad/h": 180.0 / math.pi,
    "mdeg/s": 3.6,
}
#: Raw output units that need a scale factor (raw units per deg/s).
RAW_UNITS = ("V", "mV", "Hz")
_ALIASES = {
    "°/h": "deg/h",
    "dph": "deg/h",
    "deg/hr": "deg/h",
    "°/s": "deg/s",
    "dps": "deg/s",
    "rad/sec": "rad/s",
    "v": "V",
    "volt": "V",
    "mv": "mV",
    "hz": "Hz",
}
KNOWN_UNITS = tuple(RATE_UNITS_IN_DEG_H) + RAW_UNITS


def normalise_unit(unit: str, *, file: str | None = None) -> str:
    """Return the canonical spelling of ``unit`` or raise :class:`UnitError`."""
    if unit in KNOWN_UNITS:
        return unit
    key = unit.strip()
    key = _ALIASES.get(key, _ALIASES.get(key.lower(), key))
    if key in KNOWN_UNITS:
        return key
    raise UnitError(
        f"unknown output unit '{unit}'",
        file=file,
        fix=f"use one of {', '.join(KNOWN_UNITS)}",
    )


def is_rate_unit(unit: str) -> bool:
    """True when ``unit`` is an angular rate (no scale factor needed)."""
    return normalise_unit(unit) in RATE_UNITS_IN_DEG_H


def convert_rate(values, from_unit: str, to_unit: str, *, scale_factor: float | None = None):
    """Convert ``values`` between rate units, or from a raw unit to a rate unit.

    A raw unit (V, mV, Hz) needs ``scale_factor`` in raw units per deg/s:
    ``rate[deg/s] = values / scale_factor``. Converting *to* a raw unit multiplies back.
    """
    src, dst = normalise_unit(from_unit), normalise_unit(to_unit)
    if src == dst:
        return values
    x = np.asarray(values, dtype=float)
    if src in RAW_UNITS:
        x = _require_scale(scale_factor, src) and x / scale_factor * RATE_UNITS_IN_DEG_H["deg/s"]
        src = "deg/h"
    if dst in RAW_UNITS:
        deg_s = x * RATE_UNITS_IN_DEG_H[src] / RATE_UNITS_IN_DEG_H["deg/s"]
        return deg_s * _require_scale(scale_factor, dst)
    return x * (RATE_UNITS_IN_DEG_H[src] / RATE_UNITS_IN_DEG_H[dst])


def _require_scale(scale_factor: float | None, unit: str) -> float:
    if scale_factor is None or not np.isfinite(scale_factor) or scale_factor == 0:
        raise UnitError(
            f"output unit '{unit}' is not a rate and no scale factor was given",
            fix="pass scale_factor (raw units per deg/s), e.g. --scale-factor 0.04 for 40 mV/(deg/s)",
        )
    return float(scale_factor)
