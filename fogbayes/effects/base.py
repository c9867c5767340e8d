"""The :class:`Effect` contract and the helpers its candidate generators share.

An effect enters the simulator as ``plant(params) -> [(Term, coefficients)]``, the rate
sum_j X_j(cov) c_j in deg/h with X_j the term kinds' columns (:mod:`.kinds`),
and the loop as ``candidates(ctx, terms)``: the nested terms the current model lacks.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np

from .terms import Term

Planted = list[tuple[Term, list[float]]]


class Candidate(NamedTuple):
    """One effect the model lacks.

    effect: docs/DESIGN.md name; kind: "linear" (grid of nested terms) or "spectral"
    (periodic, scanned by FFT); grid: one Term per searched
    value; covariates: the drivers it uses; searched: the searched parameter or None.
    """

    effect: str
    kind: str
    grid: tuple[Term, ...]
    covariates: tuple[str, ...]
    searched: str | None


class Effect:
    """One physical effect: subclasses set the attributes and override what differs.

    applies: "sensor" (a calibration carries it) or "run" (an event of one run); defaults:
    the simulator's parameters; size_keys: those scaled by a test record's magnitude;
    requires: covariates the simulated scenario must have ("input_rate", "temperature_2");
    same_on_top: parameters that must agree for :meth:`on_top`; max_times: how often the
    loop may add it; separable_by_programme: a chamber programme can tell it from the others
    so marked; stochastic: drawn by the scenario's noise, not planted; what: the phrase a
    separability warning names it by ("" = not examined for separability); remedy: the
    programme change that separates it ("" = the general one); processing: how the loop
    computes the covariates it uses, as the calibration document's ``processing`` states it.
    """

    name: str = ""
    applies: str = "sensor"
    description: str = ""
    defaults: dict[str, Any] = {}
    size_keys: tuple[str, ...] = ()
    requires: tuple[str, ...] = ()
    same_on_top: tuple[str, ...] = ()
    max_times: int = 1
    separable_by_programme: bool = False
    stochastic: bool = False
    what: str = ""
    remedy: str = ""
    processing: dict[str, str] = {}

    def plant(self, p: dict) -> Planted:
        raise NotImplementedError

    def complete(self, p: dict, cov) -> dict:
        """The full parameters with what depends on the record filled in."""
        return p

    def on_top(self, mine: dict, extra: dict) -> dict:
        """The scenario's parameters ``mine`` with the default ``extra`` added."""
        return mine

    def candidates(self, ctx, terms) -> list[Candidate]:
        return []

    def programme_terms(self, ctx, n: int, true: dict | None = None) -> list[Term]:
        """The terms that stand for it when a chamber programme is scored
        (:mod:`fogbayes.plan.programme`): its planted terms at ``true`` parameters (default:
        its defaults); an effect with a searched scale gives ``n`` members over the loop's
        range unless ``true`` sets the scale."""
        return [tm for tm, _ in self.plant({**self.defaults, **(true or {})})]

    def oracle(self, ctx, p: dict) -> list[Term]:
        """The planted effect at its true parameters ``p`` as the loop's terms (the true model
        is the base plus these)."""
        raise NotImplementedError(f"effect {self.name!r} has no oracle terms")


def count(terms, effect: str) -> int:
    return sum(1 for tm in terms if tm.params.get("effect") == effect)


def tpoly(terms) -> Term | None:
    for tm in terms:
        if tm.kind == "tpoly" and tm.params["channel"] == 0:
            return tm
    return None


def tscale(ctx) -> tuple[float, float]:
    T = ctx.cov.T[:, 0]
    lo, hi = float(np.min(T)), float(np.max(T))
    return 0.5 * (lo + hi), max(0.5 * (hi - lo), 1e-3)


def e(effect: str, **params) -> dict:
    return {"effect": effect, **params}


def thermal(ctx) -> bool:
    """A temperature channel that actually varies (>= 0.5 deg C)."""
    cov = ctx.cov
    return not (cov.n_temps == 0 or np.ptp(cov.T[:, 0]) < 0.5)


def rate_scale(ctx) -> float:
    return max(float(np.max(np.abs(ctx.cov.Tdot))), 1e-3)


def moving(ctx) -> bool:
    return rate_scale(ctx) > 0.02  # deg C/min: below this the record is effectively soaked


def rate_table(ctx) -> bool:
    """An input rate that varies."""
    return not (ctx.cov.omega is None or np.ptp(ctx.cov.omega) <= 0)


def wscale(ctx) -> float:
    return max(float(np.max(np.abs(ctx.cov.omega))), 1e-9)
