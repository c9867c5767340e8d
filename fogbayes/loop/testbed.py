"""Undeclared-effect test recordings for the closed loop (tests and benchmarks).

Over :func:`fogbayes.simulate.scenarios.simulate`: the scenario's model is the declared base, at
most one effect planted at ``magnitude`` x its registry default; ``oracle_terms`` gives the
true model as loop terms.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .. import effects as fx
from ..data import Recording
from ..effects.simulator_only import Paper004
from ..effects.temperature_order import TemperatureOrder
from ..simulate.registry import EFFECTS
from ..simulate.scenarios import simulate

#: Noise mixes (canonical units: N deg/sqrt(h), B deg/h, K deg/h^1.5); "default" keeps the
#: scenario's own (thermal: N 0.005, B 0.02, K 0.02).
NOISE_MIXES = {
    "default": None,
    "fog": dict(N=0.003, B=0.02, K=0.01),
    "white": dict(N=0.004),
    "flicker": dict(N=0.002, B=0.05),
    "walk": dict(N=0.003, B=0.01, K=0.05),
}

_SCENARIO = {"thermal": "thermal", "paper004": "paper004", "ratetable": "ratetable"}


class TestRecord(NamedTuple):
    recording: Recording
    effect: str | None
    effect_params: dict
    effects: dict          # name -> deterministic part (deg/h), the scenario's own included
    noise: np.ndarray


def _scaled(name: str, magnitude: float, params: dict | None) -> dict:
    base = {k: v for k, v in EFFECTS[name].defaults.items()}
    out = {}
    for k in fx.get(name).size_keys:  # the parameters that set its size
        if k in base and base[k] is not None:
            out[k] = magnitude * base[k]
    if name == TemperatureOrder.name:  # the scenario's quadratic plus the default's top power
        top = list(base["coeffs"])
        out = {"coeffs": [0.5, 0.01, 2e-4] + [0.0] * (len(top) - 4) + [magnitude * top[-1]],
               "T_ref": 20.0}
    out.update(params or {})
    return out


def make_record(effect: str | None = None, *, seed: int, duration: float = 3 * 3600.0,
                fs: float = 10.0, magnitude: float = 1.0, noise: str | dict = "default",
                effect_params: dict | None = None, temp_noise: float = 0.01,
                profile: str = "thermal", segments=None) -> TestRecord:
    """A simulated recording with ``effect`` present (None: clean) on top of the scenario.

    profile: "thermal" (generic heating/cooling test), "paper004" (room, -40, +60, room at
    1 deg C/min, soaks sized to ``duration``; its Shupe term is switched off so that the
    declared model is the quadratic bias) or "ratetable" (paper 000's grid).
    segments: a chamber programme (Soak/Ramp from 20 deg C) for profile "thermal" instead of
    the generic test; the record then lasts ``duration`` s (the end held).
    """
    opts: dict = {} if segments is None else {"segments": segments}
    effects: dict = {}
    if profile == "paper004":
        opts = {"soak": max((duration - 12000.0) / 4.0, 600.0), "ramp_rate": 1.0}
        effects[Paper004.name] = None
        effects[TemperatureOrder.name] = {"coeffs": [0.5, 0.01, 2e-4], "T_ref": 20.0}
    if effect is not None:
        effects[effect] = _scaled(effect, magnitude, effect_params)
    mix = NOISE_MIXES[noise] if isinstance(noise, str) else dict(noise)
    sim = simulate(_SCENARIO[profile], seed=seed, fs=fs,
                   duration=None if profile == "paper004" else duration, effects=effects,
                   noise=mix, temperature_noise=temp_noise, **opts)
    tr = sim.truth
    params = tr.params["effects"].get(effect, {}) if effect else {}
    return TestRecord(sim.recording, effect, params, dict(tr.effects), tr.noise)


def oracle_terms(ctx, base, effect: str, params: dict):
    """The true model as loop terms: base + the planted effect at its true parameters
    (:meth:`fogbayes.effects.Effect.oracle`)."""
    return list(base) + fx.get(effect).oracle(ctx, params)
