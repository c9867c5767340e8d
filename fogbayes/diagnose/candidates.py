"""The library of candidate effects: every docs/DESIGN.md effect name as a model term.

Each candidate is a family of :class:`~fogbayes.diagnose.terms.Term` s, one per value of its
searched parameter, added to the current model (nested, so a likelihood ratio compares them):
``temperature_order``, ``temperature_rate``, ``temperature_gradient`` (channel),
``thermal_hysteresis`` (r0 or play width), ``thermal_lag`` (tau), ``time_drift`` (form, tau),
``step`` (every block boundary, 2-98 % of the record), ``periodic`` (spectral scan) and the
scale-factor effects. Grids are coarse; :mod:`fogbayes.diagnose.refine` refines the value.
``markov_noise`` belongs to the noise model (:mod:`fogbayes.loop.noise_model`).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .context import Context
from .terms import Term

EFFECTS = ("temperature_order", "temperature_rate", "temperature_gradient", "thermal_hysteresis",
           "thermal_lag", "time_drift", "periodic", "step", "scale_factor_nonlinearity",
           "scale_factor_asymmetry", "scale_factor_temperature", "markov_noise")

#: How many times the loop may add an effect of each name.
MAX_TIMES = {"temperature_order": 3, "time_drift": 2, "step": 3, "periodic": 3,
             "scale_factor_nonlinearity": 2}


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


def _count(terms, effect: str) -> int:
    return sum(1 for tm in terms if tm.params.get("effect") == effect)


def _tpoly(terms) -> Term | None:
    for tm in terms:
        if tm.kind == "tpoly" and tm.params["channel"] == 0:
            return tm
    return None


def _tscale(ctx: Context) -> tuple[float, float]:
    T = ctx.cov.T[:, 0]
    lo, hi = float(np.min(T)), float(np.max(T))
    return 0.5 * (lo + hi), max(0.5 * (hi - lo), 1e-3)


def _e(effect: str, **params) -> dict:
    return {"effect": effect, **params}


def thermal_candidates(ctx: Context, terms) -> list[Candidate]:
    """Candidates driven by temperature (need a channel that actually varies)."""
    cov, out = ctx.cov, []
    if cov.n_temps == 0 or np.ptp(cov.T[:, 0]) < 0.5:
        return out
    centre, scale = _tscale(ctx)
    kinds = {tm.kind for tm in terms}
    tp = _tpoly(terms)
    order = max(tp.params["powers"]) if tp is not None else 0
    if _count(terms, "temperature_order") < MAX_TIMES["temperature_order"] and order < 6:
        out.append(Candidate("temperature_order", "linear", (Term("tpoly", _e(
            "temperature_order", channel=0, powers=[order + 1], centre=centre, scale=scale)),),
            ("temperature",), None))
    rate_scale = max(float(np.max(np.abs(cov.Tdot))), 1e-3)
    moving = rate_scale > 0.02  # deg C/min: below this the record is effectively soaked
    if moving and not kinds & {"rate", "rate_poly"}:
        out.append(Candidate("temperature_rate", "linear", (Term("rate", _e(
            "temperature_rate", scale=rate_scale)),), ("dT/dt",), None))
    if cov.n_temps >= 2 and "gradient" not in kinds:
        grid = []
        for j in range(1, cov.n_temps):
            d = cov.T[:, j] - cov.T[:, 0]
            if np.ptp(d) > 0.05:
                grid.append(Term("gradient", _e("temperature_gradient", a=0, b=j,
                                                scale=max(float(np.max(np.abs(d))), 1e-3))))
        if grid:
            out.append(Candidate("temperature_gradient", "linear", tuple(grid),
                                 tuple(["temperature"] + [cov.names[t.params["b"]] for t in grid]),
                                 "channel" if len(grid) > 1 else None))
    if moving and not kinds & {"hysteresis", "play"}:
        # two shapes: rate-type (tanh, back to zero in a soak) and memory (play operator,
        # held through a soak); widths from 0.5 deg C to a quarter of the range
        r0s = [r for r in (0.01, 0.02, 0.05, 0.1, 0.2, 0.5) if r < 0.5 * rate_scale]
        widths = [w for w in (0.5, 1.0, 2.0, 5.0, 10.0, 20.0) if w <= 0.25 * np.ptp(cov.T[:, 0])]
        grid = [Term("hysteresis", _e("thermal_hysteresis", r0=r)) for r in r0s] + [
            Term("play", _e("thermal_hysteresis", channel=0, width=w)) for w in widths]
        if grid:
            out.append(Candidate("thermal_hysteresis", "linear", tuple(grid), ("dT/dt",),
                                 "r0" if not widths else "r0 or width"))
    if moving and "lag" not in kinds:
        lo, hi = max(60.0, 3 * ctx.grid.dt), 0.5 * cov.duration
        if hi > 2 * lo:
            taus = np.geomspace(lo, hi, 12)
            out.append(Candidate("thermal_lag", "linear", tuple(
                Term("lag", _e("thermal_lag", channel=0, tau=float(tau), centre=centre,
                               scale=scale)) for tau in taus), ("temperature",), "tau"))
    return out


def time_candidates(ctx: Context, terms) -> list[Candidate]:
    """time_drift and step (any recording)."""
    out, dur = [], ctx.cov.duration
    have = {tm.kind for tm in terms if tm.params.get("effect") == "time_drift"}
    if _count(terms, "time_drift") < MAX_TIMES["time_drift"]:
        grid = [] if "drift_lin" in have else [Term("drift_lin", _e("time_drift", duration=dur))]
        if "drift_exp" not in have:
            grid += [Term("drift_exp", _e("time_drift", tau=float(tau)))
                     for tau in np.geomspace(dur / 100.0, dur, 10)]
        if grid:
            out.append(Candidate("time_drift", "linear", tuple(grid), ("time",), "tau"))
    if _count(terms, "step") < MAX_TIMES["step"]:
        obs = np.flatnonzero(ctx.grid.mask > 0)
        lo, hi = obs[max(1, int(0.02 * obs.size))], obs[min(obs.size - 2, int(0.98 * obs.size))]
        pos = np.arange(lo, hi + 1)  # every block boundary (module doc)
        times = ctx.grid.t[pos] - 0.5 * ctx.grid.dt  # block boundaries
        out.append(Candidate("step", "linear", tuple(
            Term("step", _e("step", time=float(tm))) for tm in times), ("time",), "time"))
    return out


def rate_table_candidates(ctx: Context, terms) -> list[Candidate]:
    """Scale-factor candidates (need an input rate that varies)."""
    cov, out = ctx.cov, []
    if cov.omega is None or np.ptp(cov.omega) <= 0:
        return out
    kinds = {tm.kind for tm in terms}
    wpow = [e for tm in terms if tm.kind == "omega_poly" for e in tm.params["powers"]]
    wscale = max(float(np.max(np.abs(cov.omega))), 1e-9)
    top = max(wpow) if wpow else 1
    if _count(terms, "scale_factor_nonlinearity") < MAX_TIMES["scale_factor_nonlinearity"] \
            and top < 6:
        out.append(Candidate("scale_factor_nonlinearity", "linear", (
            Term("omega_poly", _e("scale_factor_nonlinearity", powers=[top + 1], scale=wscale)),
            Term("omega_poly", _e("scale_factor_nonlinearity", powers=[top + 1, top + 2],
                                  scale=wscale))), ("input_rate",), "order"))
    if "omega_abs" not in kinds:
        out.append(Candidate("scale_factor_asymmetry", "linear", (Term("omega_abs", _e(
            "scale_factor_asymmetry", scale=wscale)),), ("input_rate",), None))
    if cov.n_temps and np.ptp(cov.T[:, 0]) >= 0.5:
        centre, scale = _tscale(ctx)
        tpow = [e for tm in terms if tm.kind == "omega_tpoly" and tm.params.get("wpower", 1) == 1
                for e in tm.params["powers"]]
        k = (max(tpow) if tpow else 0) + 1
        if k <= 4:
            out.append(Candidate("scale_factor_temperature", "linear", (Term("omega_tpoly", _e(
                "scale_factor_temperature", channel=0, powers=[k], centre=centre,
                t_scale=scale, scale=wscale)),), ("input_rate", "temperature"), None))
    return out


def periodic_candidate(ctx: Context, terms) -> list[Candidate]:
    if _count(terms, "periodic") >= MAX_TIMES["periodic"]:
        return []
    return [Candidate("periodic", "spectral", (), ("time",), "frequency")]


def candidates_for(ctx: Context, terms, *,
                   effects: tuple[str, ...] | None = None) -> list[Candidate]:
    """Every deterministic candidate the current model (``terms``) lacks."""
    out = (thermal_candidates(ctx, terms) + time_candidates(ctx, terms)
           + rate_table_candidates(ctx, terms) + periodic_candidate(ctx, terms))
    if effects is not None:
        out = [c for c in out if c.effect in effects]
    return out
