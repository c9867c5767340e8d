"""The simulator's view of :mod:`fogbayes.effects`: default parameters, help, planted rate.

``effect_rate(name, cov, params)`` in deg/h from :class:`~fogbayes.simulate.truth.Covariates`;
``EffectSpec.terms(params)`` plants each through the loop's term kinds
(:mod:`fogbayes.effects.kinds`); closed forms in :mod:`fogbayes.simulate.effects` are the
independent reference. ``markov_noise`` is drawn by the scenario.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, Callable, NamedTuple

import numpy as np

from .. import effects
from ..preprocess.covariates import Covariates as TermCovariates
from ..effects.terms import design
from ..effects import Planted
from ._checks import SimulationParameterError
from .truth import Covariates


class EffectSpec(NamedTuple):
    fn: Callable[[Covariates, dict], np.ndarray] | None  # None: stochastic (markov_noise)
    defaults: dict[str, Any]
    description: str
    terms: Callable[[dict], Planted] | None = None  # the effect as loop terms (module doc)


def term_covariates(c: Covariates) -> TermCovariates:
    """The simulator's true covariates as the loop's term covariates (same clock)."""
    names = tuple(f"T{j + 1}" for j in range(c.temperatures.shape[1]))
    return TermCovariates(np.asarray(c.time, float), np.asarray(c.temperatures, float), names,
                          np.asarray(c.dTdt, float), c.input_rate,
                          float(c.time[-1] - c.time[0]), c.operating_time)


def _require(name: str, needs: tuple[str, ...], cov: Covariates) -> None:
    """Raise when the scenario lacks a covariate the effect acts on."""
    if "input_rate" in needs and cov.input_rate is None:
        raise SimulationParameterError(
            f"effect '{name}' acts on the input rate but this scenario has none",
            column=name, fix="use the 'ratetable' or 'paper000' scenario, or pass input_rate=")
    if "temperature_2" in needs and cov.temperatures.shape[1] < 2:
        raise SimulationParameterError(
            f"effect '{name}' needs two temperature channels, this scenario has "
            f"{cov.temperatures.shape[1]}", column=name, fix="use a scenario with two channels")


def _planted(eff: effects.Effect) -> Callable[[Covariates, dict], np.ndarray]:
    """An effect's rate from its terms: sum_j X_j(cov) c_j (deg/h)."""
    def fn(c: Covariates, p: dict) -> np.ndarray:
        _require(eff.name, eff.requires, c)
        pairs = eff.plant(p)
        X = design([t for t, _ in pairs], term_covariates(c))
        return X @ np.concatenate([np.asarray(k, float) for _, k in pairs])
    return fn


class _Specs(Mapping):
    """Every registered effect and law as an :class:`EffectSpec`, read from the registry on
    each access (an effect registered later is simulated too)."""

    def _names(self) -> list[str]:
        return [*effects.REGISTRY, *effects.LAWS]

    def __getitem__(self, name: str) -> EffectSpec:
        eff = effects.get(name)
        if eff.stochastic:
            return EffectSpec(None, eff.defaults, eff.description)
        return EffectSpec(_planted(eff), eff.defaults, eff.description, eff.plant)

    def __iter__(self):
        return iter(self._names())

    def __len__(self) -> int:
        return len(self._names())

    def __contains__(self, name) -> bool:
        return name in effects.REGISTRY or name in effects.LAWS


EFFECTS: Mapping[str, EffectSpec] = _Specs()


def _number(v) -> bool:
    return isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, bool) \
        and bool(np.isfinite(v))


def resolve(name: str, params: dict | None, cov: Covariates) -> dict[str, Any]:
    """The effect's full parameter set: defaults updated by ``params``; unknown keys raise."""
    if name not in EFFECTS:
        raise SimulationParameterError(f"unknown effect '{name}'", argument="effects",
                                       fix=f"use one of {', '.join(sorted(EFFECTS))}")
    spec = EFFECTS[name]
    params = dict(params or {})
    bad = set(params) - set(spec.defaults)
    if bad:
        raise SimulationParameterError(
            f"effect '{name}' has no parameter(s) {sorted(bad)}", column=name,
            fix=f"use {sorted(spec.defaults)}")
    for key, value in params.items():  # numbers where the default is a number or a list
        want = spec.defaults[key]
        listed = isinstance(want, (list, tuple))
        if listed:
            ok = isinstance(value, (list, tuple, np.ndarray)) and \
                all(_number(v) for v in np.ravel(np.asarray(value, dtype=object)))
        else:
            ok = _number(value) or (want is None and value is None)
        if not ok:
            what = "a list of numbers" if listed else "a finite number"
            raise SimulationParameterError(f"effect '{name}': {key}={value!r} is not {what}",
                                           column=name, fix=f"give e.g. {key}={want!r}")
    return effects.get(name).complete({**spec.defaults, **params}, cov)


def on_top(name: str, own: dict, cov: Covariates) -> dict[str, Any]:
    """Parameters of effect ``name`` at its registry default *added to* the scenario's ``own``
    (:meth:`~fogbayes.effects.Effect.on_top`): naming an effect that the scenario's model
    already has must plant something the declared model lacks."""
    mine, extra = resolve(name, own, cov), resolve(name, None, cov)
    for key in effects.get(name).same_on_top:
        if extra[key] != mine[key]:
            raise SimulationParameterError(
                f"{name} on top of the scenario's needs the same {key}",
                column=name, fix=f"give the full coefficients with {key} {mine[key]}")
    return effects.get(name).on_top(mine, extra)


def effect_rate(name: str, cov: Covariates, params: dict) -> np.ndarray:
    """Deterministic effect ``name`` in deg/h with the full parameters ``params``."""
    return np.broadcast_to(EFFECTS[name].fn(cov, params), cov.time.shape).astype(float)
