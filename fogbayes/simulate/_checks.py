"""Argument checks shared by the simulator (bad arguments raise a FogbayesError)."""

from __future__ import annotations

import math

from ..errors import ArgumentError


class SimulationParameterError(ArgumentError):
    """A simulator argument is out of range (negative noise level, unknown effect, ...)."""


def positive_int(value, name: str, *, minimum: int = 1) -> int:
    """``value`` as an int >= ``minimum``, else raise naming the argument."""
    if isinstance(value, bool) or int(value) != value or int(value) < minimum:
        raise SimulationParameterError(f"{name} must be an integer >= {minimum}, got {value!r}",
                                       column=name, fix=f"pass {name}={minimum} or more")
    return int(value)


def positive(value, name: str, *, allow_zero: bool = False) -> float:
    """``value`` as a finite float > 0 (or >= 0 with ``allow_zero``)."""
    v = float(value)
    ok = math.isfinite(v) and (v >= 0 if allow_zero else v > 0)
    if not ok:
        bound = ">= 0" if allow_zero else "> 0"
        raise SimulationParameterError(f"{name} must be finite and {bound}, got {value!r}",
                                       column=name, fix=f"give {name} {bound}")
    return v


def seed_int(seed, name: str = "seed") -> int:
    """A seed must be a non-negative int (given explicitly, never drawn at random)."""
    if isinstance(seed, bool) or not isinstance(seed, (int,)) and not hasattr(seed, "__index__"):
        raise SimulationParameterError(f"{name} must be a non-negative integer, got {seed!r}",
                                       column=name, fix=f"pass {name}=0 (or any int >= 0)")
    s = int(seed)
    if s < 0:
        raise SimulationParameterError(f"{name} must be >= 0, got {seed!r}", column=name,
                                       fix=f"pass {name}=0 (or any int >= 0)")
    return s
