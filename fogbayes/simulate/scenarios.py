"""Named simulation scenarios: ``simulate(name, *, seed, ...) -> Simulated(recording, truth)``.

output = sum(truth.effects) + sum(truth.noise_parts), specified in deg/h and converted to the
output unit (deg/h, deg/s, rad/s, or raw units via ``scale_factor``).
"""

from __future__ import annotations

import zlib
from typing import Any, Callable, NamedTuple

import numpy as np

from ..data.recording import Metadata, Recording
from ..data.units import RATE_UNITS_IN_DEG_H, RAW_UNITS, normalise_unit
from ..effects.simulator_only import Paper004
from ..effects.temperature_order import TemperatureOrder
from . import effects as fx
from . import profiles as pf
from ._checks import SimulationParameterError, positive, seed_int
from .noise import allan_noise, arma_noise, markov_noise, sinusoid
from .registry import EFFECTS, effect_rate, on_top, resolve
from .truth import Covariates, Simulated, Truth

#: Scenario names and one-line descriptions (listed by ``fogbayes simulate``).
SCENARIOS: dict[str, str] = {
    "thermal": "6.3 h heating/cooling chamber test at 10 Hz, quadratic bias in T, FOG-like noise "
               "(white + flicker + small RRW), two lagging temperature channels (deg/h)",
    "paper004": "paper 004 verification profile (room, -40, +60, room; 2 h soaks, 0.5 C/min) at "
                "1 Hz, order-2 bias in T and dT/dt (Shupe) (deg/h)",
    "paper000": "paper 000 rate table (10 temperatures x 14 rates), composite model with the "
                "eq. 15/16/12 coefficients, output in V with input_rate",
    "ratetable": "paper 000's rate-table grid in deg/h: nominal scale 3600 w + quadratic bias "
                 "in T; plant scale-factor effects here",
    "static": "1 h static record at 10 Hz, Allan noise only, constant 20 C",
}


class _Base(NamedTuple):
    cov: Covariates
    names: tuple[str, ...]
    native: dict[str, np.ndarray]  # the scenario's own components, already in output units
    effects: dict[str, dict]  # default extra effects (deg/h)
    noise: dict[str, Any]  # default noise (deg/h)
    profile: dict[str, Any]  # JSON-able profile settings
    fs: float
    unit: str = "deg/h"
    scale_factor: float | None = None


def _sub(seed: int, name: str) -> int:
    """Independent seed for one component: changing one never changes another."""
    return int(np.random.SeedSequence([seed, zlib.crc32(name.encode())]).generate_state(1)[0])


def _rate_cov(t, temps, chamber=None, omega=None, op=None, *, rates=None) -> Covariates:
    """True covariates; ``rates`` (n, k) the channels' exact dT/dt (deg C/min,
    :func:`profiles.sensor_rates`), None on a soaked record (dT/dt = 0)."""
    dTdt = np.zeros_like(t) if rates is None else np.asarray(rates[:, 0], dtype=float)
    return Covariates(t, temps[:, 0], temps, dTdt, omega, chamber, op)


def _input(omega, n) -> np.ndarray | None:
    return None if omega is None else np.broadcast_to(np.asarray(omega, float), (n,)).copy()


def _thermal(fs, duration, *, lags=(300.0, 900.0), input_rate=None, segments=None,
             **levels) -> _Base:
    if segments is None:  # the generic heating/cooling test, sized to the duration
        p = pf.thermal_test_profile(fs=fs or 10.0, duration=duration or 6.3 * 3600.0,
                                    lags=lags, **levels)
    else:  # a given chamber programme (Soak/Ramp segments from ``levels["room"]``)
        segments = pf.as_segments(segments)
        p = pf.thermal_profile(segments, fs=fs or 10.0, start=levels.get("room", 20.0),
                               lags=lags, duration=duration)
        duration = p.time[-1] + 1.0 / (fs or 10.0)
        levels = {**levels, "segments": pf.segments_json(segments)}
    cov = _rate_cov(p.time, p.temperatures, p.chamber, _input(input_rate, p.time.size),
                    rates=p.rates)
    return _Base(cov, p.names, {}, {TemperatureOrder.name: {"coeffs": [0.5, 0.01, 2e-4],
                                                            "T_ref": 20.0}},
                 {"N": 0.005, "B": 0.02, "K": 0.02},
                 {"kind": "thermal_test", "duration": duration or 6.3 * 3600.0,
                  "lags": list(p.lags), **levels}, fs or 10.0)


# paper004's defaults reproduce the paper's full-temperature bias stability on 1 s data:
# measured over seeds 0-3, 1.64 deg/h before and 0.49 after removing the model (paper: 1.6457
# -> 0.5015); the noise alone gives the paper's soak stability (0.38-0.45 deg/h).
def _paper004(fs, duration, *, soak=7200.0, ramp_rate=0.5, lags=(300.0, 900.0),
              input_rate=None, **temps) -> _Base:
    segs = pf.paper004_segments(soak=soak, ramp_rate=ramp_rate, **temps)
    p = pf.thermal_profile(segs, fs=fs or 1.0, start=segs[0].temperature, lags=lags,
                           duration=duration)
    cov = _rate_cov(p.time, p.temperatures, p.chamber, _input(input_rate, p.time.size),
                    rates=p.rates)
    return _Base(cov, p.names, {},
                 {Paper004.name: {"c": [0.3, 0.03, 6e-4], "d": [4.0, 0.0], "cross": 0.0,
                                  "T_ref": 20.0}},
                 {"N": 0.008, "B": 0.05},
                 {"kind": "paper004", "soak": soak, "ramp_rate": ramp_rate, "lags": list(lags),
                  **temps}, fs or 1.0)


def _static(fs, duration, *, temperature=20.0) -> _Base:
    t = pf.time_grid(duration or 3600.0, fs or 10.0)
    temps = np.full((t.size, 1), float(temperature))
    return _Base(_rate_cov(t, temps), ("temperature",), {}, {},
                 {"N": 0.005, "B": 0.02, "K": 0.05}, {"kind": "static", "temperature": temperature},
                 fs or 10.0)


def _grid(fs, duration, temperatures, rates, dwell, restart):
    if duration is not None:  # size the dwell so the whole grid fits in `duration`
        dwell = positive(duration, "duration") / (len(temperatures) * len(rates))
    s = pf.rate_table_schedule(fs=fs or 1.0, dwell=dwell, temperatures=temperatures,
                               rates=rates, restart=restart)
    cov = _rate_cov(s.time, s.temperature[:, None], s.temperature, s.input_rate,
                    s.operating_time)
    prof = {"kind": "rate_table", "dwell": dwell, "temperatures": list(s.temperatures),
            "rates": list(s.rates), "restart": restart}
    return cov, prof


def _paper000(fs, duration, *, dwell=60.0, temperatures=pf.PAPER000_TEMPERATURES,
              rates=pf.PAPER000_RATES, restart="cell", M=fx.PAPER000_M, c=fx.PAPER000_U0,
              d=fx.PAPER000_U1) -> _Base:
    cov, prof = _grid(fs, duration, temperatures, rates, dwell, restart)
    M, c, d = (np.asarray(x, dtype=float) for x in (M, c, d))
    sf = float(M[0, 0])
    T, w = cov.temperature, cov.input_rate
    native = {"input": sf * w,
              "paper000_scale": fx.paper000_scale(T, w, M=M) - sf * w,
              "paper000_bias": fx.paper000_bias(T, c=c),
              "paper000_drift": fx.paper000_drift(T, cov.operating_time, d=d)}
    prof["model"] = {"M": M.tolist(), "c": c.tolist(), "d": d.tolist()}
    return _Base(cov, ("temperature",), native, {}, {"N": 0.05, "B": 0.2}, prof, fs or 1.0,
                 unit="V", scale_factor=sf)


def _ratetable(fs, duration, *, dwell=60.0, temperatures=pf.PAPER000_TEMPERATURES,
               rates=pf.PAPER000_RATES, restart="cell") -> _Base:
    cov, prof = _grid(fs, duration, temperatures, rates, dwell, restart)
    return _Base(cov, ("temperature",), {}, {TemperatureOrder.name: {
                     "coeffs": [0.5, 0.01, 2e-4], "T_ref": 20.0}},
                 {"N": 0.005, "B": 0.02}, prof, fs or 1.0)


_BUILDERS: dict[str, Callable[..., _Base]] = {
    "thermal": _thermal, "paper004": _paper004, "paper000": _paper000,
    "ratetable": _ratetable, "static": _static,
}
_ALLAN = ("Q", "N", "B", "K", "R")
_NOISE_KEYS = _ALLAN + ("markov", "arma", "sinusoid")


def _deg_h_to_output(unit: str, scale_factor: float | None) -> float:
    """Factor turning a rate in deg/h into the output unit."""
    if unit in RAW_UNITS:
        if not scale_factor:
            raise SimulationParameterError(f"output unit {unit} needs a scale factor",
                                           argument="scale_factor",
                                           fix="pass scale_factor= in raw units per deg/s")
        return scale_factor / 3600.0
    return 1.0 / RATE_UNITS_IN_DEG_H[unit]


def _noise_parts(spec: dict, n: int, fs: float, seed: int) -> dict[str, np.ndarray]:
    bad = set(spec) - set(_NOISE_KEYS)
    if bad:
        raise SimulationParameterError(f"unknown noise term(s) {sorted(bad)}", argument="noise",
                                       fix=f"use {', '.join(_NOISE_KEYS)}")
    parts = {}
    allan = {k: spec[k] for k in _ALLAN if spec.get(k)}
    if allan:
        parts["allan"] = allan_noise(n, fs, seed=_sub(seed, "allan"), **allan)
    if spec.get("markov"):
        parts["markov"] = markov_noise(n, fs, seed=_sub(seed, "markov"), **spec["markov"])
    if spec.get("arma"):
        parts["arma"] = arma_noise(n, seed=_sub(seed, "arma"), **spec["arma"])
    if spec.get("sinusoid"):
        parts["sinusoid"] = sinusoid(n, fs, **spec["sinusoid"])
    return parts


def _jsonable(v):
    """Parameters as plain JSON types (lists, floats) for files and reports."""
    if isinstance(v, dict):
        return {str(k): _jsonable(x) for k, x in v.items()}
    if isinstance(v, np.ndarray):
        return v.tolist()
    if isinstance(v, (list, tuple)):
        return [_jsonable(x) for x in v]
    if isinstance(v, np.generic):
        return v.item()
    return v


def simulate(scenario: str = "thermal", *, seed: int, fs: float | None = None,
             duration: float | None = None, effects: dict | None = None,
             noise: dict | None = None, unit: str | None = None,
             scale_factor: float | None = None, temperature_noise: float = 0.0,
             sensor_id: str | None = None, **options) -> Simulated:
    """Simulate a named scenario (see :data:`SCENARIOS`) with known truth.

    Args:
        scenario: a key of :data:`SCENARIOS`.
        seed: explicit integer seed; the same seed gives the same data.
        fs: sample rate (Hz); duration: length (s) (scenario defaults when None; for rate
            tables the dwell is sized so the grid fits in ``duration``).
        effects: extra effects by name -> parameters (deg/h), merged over the scenario's
            defaults and each effect's default parameters; ``{name: None}`` removes one.
            A bare name (``{}``) of an effect the scenario's model already has adds the
            effect's default on top (thermal/ratetable ``temperature_order``: the registry's
            cubic on top of the scenario's quadratic, :func:`registry.on_top`); given
            parameters replace the scenario's.
        noise: replaces the scenario's noise: Allan terms ``Q N B K R`` (canonical units,
            see :mod:`~fogbayes.simulate.noise`) and optional ``markov`` {sigma, tau_c},
            ``arma`` {phi, theta, sigma}, ``sinusoid`` {amplitude, frequency, phase}, all
            deg/h; ``noise={}`` gives a noise-free record.
        unit / scale_factor: output unit for deg/h scenarios (V/Hz need ``scale_factor``).
        temperature_noise: std (deg C) of white noise on the recorded temperatures only.
        **options: scenario settings, e.g. thermal: ``lags, input_rate, room, low, high``;
            paper004: ``soak, ramp_rate, lags, room, cold, hot``; static: ``temperature``;
            paper000/ratetable: ``dwell, temperatures, rates, restart`` (+ ``M, c, d``).

    Example:
        >>> import numpy as np
        >>> sim = simulate("thermal", seed=0, duration=600.0, fs=1.0)
        >>> bool(np.allclose(sim.recording.output, sim.truth.deterministic + sim.truth.noise))
        True
    """
    if scenario not in _BUILDERS:
        raise SimulationParameterError(f"unknown scenario '{scenario}'", argument="scenario",
                                       fix=f"use one of {', '.join(SCENARIOS)}")
    seed = seed_int(seed)
    if fs is not None:  # 0 must not fall back to the default through `fs or 10.0`
        fs = positive(fs, "fs")
    if duration is not None:
        duration = positive(duration, "duration")
    try:
        base = _BUILDERS[scenario](fs, duration, **options)
    except TypeError as exc:  # an option this scenario does not take
        if "keyword argument" not in str(exc):
            raise
        raise SimulationParameterError(f"scenario '{scenario}': {exc}", argument="options",
                                       fix="see help(fogbayes.simulate.simulate)") from None
    cov = base.cov
    n, fs_ = cov.time.size, base.fs
    out_unit = normalise_unit(unit) if unit else base.unit
    sf = scale_factor if scale_factor is not None else base.scale_factor
    if base.native and out_unit != base.unit:
        raise SimulationParameterError(f"scenario '{scenario}' is simulated in {base.unit}",
                                       argument="unit", fix=f"drop unit= or use {base.unit}")
    k = _deg_h_to_output(out_unit, sf)

    comps = dict(base.native)
    if cov.input_rate is not None and "input" not in comps:
        comps["input"] = 3600.0 * k * cov.input_rate  # nominal response, scale 3600 deg/h per deg/s
    merged = {**base.effects, **(effects or {})}
    used, noise_parts = {}, {}
    for name, params in merged.items():
        if params is None:
            continue
        if name in comps:
            raise SimulationParameterError(f"'{name}' is part of the scenario's model",
                                           argument="effects", fix="use an effect name")
        own = base.effects.get(name)
        if own is not None and params == {} and name in (effects or {}):
            full = on_top(name, own, cov)  # a bare name adds the effect to the scenario's
        else:
            full = resolve(name, {**(own or {}), **params}, cov)
        used[name] = full
        if EFFECTS[name].fn is None:  # markov_noise: stochastic, drawn with its own stream
            noise_parts[name] = k * markov_noise(n, fs_, seed=_sub(seed, name), **full)
        else:
            comps[name] = k * effect_rate(name, cov, full)
    nspec = base.noise if noise is None else dict(noise)
    for key, part in _noise_parts(nspec, n, fs_, seed).items():
        noise_parts[key] = k * part

    det = np.sum(list(comps.values()), axis=0) if comps else np.zeros(n)
    nz = np.sum(list(noise_parts.values()), axis=0) if noise_parts else np.zeros(n)
    temps = cov.temperatures
    if temperature_noise:
        rng = np.random.default_rng(_sub(seed, "temperature"))
        temps = temps + positive(temperature_noise, "temperature_noise") * \
            rng.standard_normal(temps.shape)
    params = _jsonable({"scenario": scenario, "seed": seed, "fs": fs_, "unit": out_unit,
                        "scale_factor": sf, "effects": used, "noise": nspec,
                        "profile": base.profile, "temperature_noise": temperature_noise})
    meta = Metadata(sensor_id=sensor_id or f"sim-{scenario}-{seed}", sample_rate=fs_,
                    source=None, extra={"simulated": True, "scenario": scenario, "seed": seed})
    rec = Recording(time=cov.time, output=det + nz, unit=out_unit, temperatures=temps,
                    temperature_names=base.names, input_rate=cov.input_rate,
                    scale_factor=sf, meta=meta)
    truth = Truth(comps, det, nz, noise_parts, params, cov)
    return Simulated(rec, truth)
