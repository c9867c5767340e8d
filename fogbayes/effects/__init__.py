"""The effect registry: one :class:`Effect` per physical effect, by its docs/DESIGN.md name.

:data:`REGISTRY` (DESIGN.md order) is what the loop searches (``candidates``) and the simulator
plants (``plant``); :data:`LAWS` holds simulator-only composite laws (paper 004's bias).
:func:`register` adds an effect (usable as a class decorator), :func:`unregister` removes it.
"""

from __future__ import annotations

from .base import Candidate, Effect, Planted
from .periodic import Periodic
from .scale_factor import ScaleFactorAsymmetry, ScaleFactorNonlinearity, ScaleFactorTemperature
from .simulator_only import MarkovNoise, Paper004
from .step import Step
from .temperature_gradient import TemperatureGradient
from .temperature_order import TemperatureOrder
from .temperature_rate import TemperatureRate
from .thermal_hysteresis import ThermalHysteresis
from .thermal_lag import ThermalLag
from .time_drift import TimeDrift

REGISTRY: dict[str, Effect] = {e.name: e() for e in (
    TemperatureOrder, TemperatureRate, TemperatureGradient, ThermalHysteresis, ThermalLag,
    TimeDrift, Periodic, Step, ScaleFactorNonlinearity, ScaleFactorAsymmetry,
    ScaleFactorTemperature, MarkovNoise)}
LAWS: dict[str, Effect] = {Paper004.name: Paper004()}


def register(effect):
    """Add ``effect`` (an :class:`Effect` subclass or instance) under its name; returns it."""
    inst = effect() if isinstance(effect, type) else effect
    if not inst.name or inst.name in REGISTRY or inst.name in LAWS:
        raise ValueError(f"effect name {inst.name!r} is empty or already registered")
    REGISTRY[inst.name] = inst
    return effect


def unregister(name: str) -> None:
    REGISTRY.pop(name)


def get(name: str) -> Effect:
    """The registered effect or simulator law ``name`` (KeyError otherwise)."""
    return REGISTRY[name] if name in REGISTRY else LAWS[name]


__all__ = ["Candidate", "Effect", "LAWS", "Planted", "REGISTRY", "get", "register",
           "unregister"]
