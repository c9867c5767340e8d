"""What a simulation returns: the Recording and the truth behind it."""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np

from ..data.recording import Recording


class Covariates(NamedTuple):
    """The true (noise-free) drivers of the effects, one value per sample.

    time s; temperature (n,) first sensor channel deg C; temperatures (n, k) all channels;
    dTdt deg C/min of the first channel, the exact derivative of its true temperature
    (:func:`~fogbayes.simulate.profiles.sensor_rates`: tau dT/dt = T_chamber - T, no
    finite difference, no smoothing; 0 on a soaked record); input_rate deg/s or
    None; chamber deg C or None; operating_time s (paper 000's t) or None.
    """

    time: np.ndarray
    temperature: np.ndarray
    temperatures: np.ndarray
    dTdt: np.ndarray
    input_rate: np.ndarray | None = None
    chamber: np.ndarray | None = None
    operating_time: np.ndarray | None = None


class Truth(NamedTuple):
    """The known answer behind a simulated Recording (all arrays in the output unit).

    recording.output == deterministic + noise (exactly, to rounding), where
    deterministic == sum(effects.values()) and noise == sum(noise_parts.values()).

    effects: deterministic component of every effect by name ("input" is the nominal
        response to the input rate, scale * omega; paper 000's model appears as
        "paper000_scale", "paper000_bias", "paper000_drift"; paper 004's as "paper004").
    noise_parts: stochastic components ("allan", "arma", "sinusoid", and each stochastic
        effect by its name).
    params: JSON-able true parameters: {"scenario", "seed", "fs", "unit",
        "scale_factor", "effects": {name: params}, "noise": {...}, "profile": {...}}.
    covariates: the true drivers (see :class:`Covariates`); recorded temperatures may
        carry measurement noise, these do not.
    """

    effects: dict[str, np.ndarray]
    deterministic: np.ndarray
    noise: np.ndarray
    noise_parts: dict[str, np.ndarray]
    params: dict[str, Any]
    covariates: Covariates

    def error(self) -> np.ndarray:
        """Deterministic error: everything deterministic except the nominal input response."""
        return self.deterministic - self.effects.get("input", 0.0)


class Simulated(NamedTuple):
    """``simulate(...)`` result: the data and its truth."""

    recording: Recording
    truth: Truth
