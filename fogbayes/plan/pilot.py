"""Plan a static record's length from a short pilot recording.

GLS fit of the pilot (:func:`fogbayes.allan.fit.fit_range`); terms whose 90 % interval reaches 0
are dropped (R first; unplannable: :class:`~fogbayes.plan.length.PlanError`; ``terms`` limits
them). Point plan :func:`fogbayes.plan.length.plan_length` at the estimate; range over the
pilot's 90 % region (:mod:`fogbayes.plan.spread`), its long end also with each unresolved term
but R at its 90 % upper bound (``range.assumed``); ``ends`` one term at a time. Beyond
``max_days`` a range end is infinite.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from .. import __version__
from ..allan.data import prepare
from ..allan.fit import AllanFit, fit_range, fit_wls
from ..allan.model import TERMS, UNITS
from .length import MAX_DAYS, LengthPlan, PlanError, _validate, describe, half_width, \
    log_cov, plan_length
from .spread import PlanRange, plan_range

PLAN_SCHEMA = "fogbayes.plan/1"


class PilotPlan(NamedTuple):
    """A length plan from a pilot: its fit, the point plan and the range over its intervals."""

    term: str
    precision: float
    level: float
    fs: float
    pilot_n: int
    fit: AllanFit          # GLS fit of the pilot on the model's terms
    terms: tuple           # the model: terms the pilot resolves
    dropped_terms: tuple   # terms left out as unresolved, in the order dropped
    taus_left_out: int     # shortest octaves left out by fit_range
    tau_min: float         # s
    pilot_width: float     # relative half-width of ``term`` from the pilot itself, at level
    plan: LengthPlan       # at the pilot's estimate
    range: PlanRange       # over the pilot's joint 90 % region
    assumed: dict          # unresolved terms at their upper bound in the range's long end
    ends: dict             # term -> {"low": (value, LengthPlan | None), "high": (...)}

    @property
    def range_hours(self) -> tuple[float, float]:
        """(shortest, longest) planned hours over the pilot's region; inf = beyond max_days."""
        return self.range.hours


#: goodness-of-fit p below which the pilot's model is refused (far below the fit's own
#: GOF_LEVEL 1e-3, where it only widens its errors: a model this wrong has no errors to widen)
MISFIT_P = 1e-6


def pilot_model(data, terms=TERMS) -> tuple[AllanFit, tuple, tuple]:
    """Backward elimination of unresolved terms (module docstring, step 2).

    Returns the final GLS fit, its terms and the terms dropped (in order)."""
    terms, dropped = [t for t in TERMS if t in terms], []
    while True:
        fit = fit_wls(data, terms)
        weak = [t for t in terms if not fit.terms[t].low > 0]
        if not weak or len(terms) == 1:
            return fit, tuple(terms), tuple(dropped)
        # R first: on a short pilot the last octaves cannot tell slope +1/2 from +1, and a
        # ramp (a drift, not noise) is the term a static run least often shows
        worst = "R" if "R" in weak else min(weak, key=lambda t: fit.info["d_chi2_without"][t])
        terms.remove(worst)
        dropped.append(worst)


def plan_from_pilot(rate_deg_h, fs: float, term: str, precision: float, *,
                    level: float = 0.9, max_days: float = MAX_DAYS,
                    terms=TERMS) -> PilotPlan:
    """Plan the record length for ``term`` to ``precision`` at ``level`` from a pilot record
    (rate in deg/h at ``fs`` Hz, NaN = missing sample); see the module docstring."""
    _validate(term, float(precision), float(level), float(max_days))
    rate = np.asarray(rate_deg_h, float)
    full = prepare(rate, fs)
    if not np.all(full.avar > 0):
        raise PlanError("the pilot's Allan variance is zero at some tau (a constant or "
                        "stuck output)", column="output",
                        fix="check the column: a static gyro's output is never constant")
    data, _, left_out = fit_range(full, terms)
    fit, model, dropped = pilot_model(data, terms)
    hours = full.n / fs / 3600.0
    if fit.info["gof_p"] < MISFIT_P:  # e.g. --terms K on a white-noise pilot: K = white
        raise PlanError(
            f"the pilot's Allan variance is not described by the terms {', '.join(model)} "
            f"(goodness-of-fit p = {fit.info['gof_p']:.2g}): a plan from that model would be "
            "wrong", column="terms",
            fix=f"let the pilot's fit choose among more terms (e.g. --terms {','.join(TERMS)})")
    if term not in model:
        est = fit_wls(data, tuple(model) + (term,)).terms[term] if term in terms else None
        seen = "" if est is None else (f" ({term} = {est.value:.3g} [{est.low:.3g}, "
                                       f"{est.high:.3g}] {est.unit} with it in the model)")
        raise PlanError(
            f"the {hours:.3g} h pilot does not resolve {term}: its 90 % interval reaches 0"
            f"{seen}, so no length can be planned from it", column="term",
            fix=f"record a longer pilot ({term} must show in the ADEV curve), or plan from "
                "datasheet values with fogbayes.plan.plan_length(AllanParams(...), fs, "
                f"'{term}', {precision:g})")
    tau_min = float(data.tau[0])
    kw = dict(level=level, terms=model, tau_min=tau_min, max_days=max_days)
    plan = plan_length(fit.params, fs, term, precision, **kw)
    cov = log_cov(fit.params, data, model)[1] * fit.info["dispersion"]
    spread = plan_range(fit.params, cov, fs, term, precision, **kw)
    assumed = {t: float(fit_wls(data, tuple(model) + (t,)).terms[t].high)
               for t in dropped if t not in ("R", term)}
    if assumed:  # step 5: the unresolved terms at their upper bounds, for the long end
        wide = fit.params._replace(**assumed)
        big = tuple(t for t in TERMS if t in model or t in assumed)
        pad = np.zeros((len(big), len(big)))
        idx = [big.index(t) for t in model]
        pad[np.ix_(idx, idx)] = cov
        pad[np.diag_indices(len(big))] += 1e-12  # fixed: no spread of their own
        longer = plan_range(wide, pad, fs, term, precision, **{**kw, "terms": big})
        if longer.hours[1] > spread.hours[1]:
            spread = spread._replace(n_high=longer.n_high, params_high=longer.params_high)
    ends: dict = {}
    for t in model:
        est = fit.terms[t]
        ends[t] = {}
        for which, v in (("low", est.low), ("high", est.high)):
            p = fit.params._replace(**{t: float(v)})
            ends[t][which] = (float(v), plan_length(p, fs, term, precision, refuse=False, **kw))
    se = float(fit.info["se_log"][TERMS.index(term)])
    return PilotPlan(term, float(precision), float(level), float(fs), int(full.n), fit, model,
                     dropped, int(left_out), tau_min, float(half_width(se, level)), plan,
                     spread, assumed, ends)


def _hours(x: float) -> float | None:
    return None if not math.isfinite(x) else x


def plan_document(pp: PilotPlan, *, source: str | None = None,
                  sensor_id: str | None = None) -> dict:
    """The JSON-able document of a :class:`PilotPlan` (hours ``null`` = beyond max_days)."""
    fit = pp.fit
    ends = {t: {w: {"value": v, "hours": None if one is None else one.hours,
                    "n": None if one is None else one.n}
                for w, (v, one) in e.items()} for t, e in pp.ends.items()}
    return {
        "schema": PLAN_SCHEMA, "fogbayes_version": __version__, "source": source,
        "sensor_id": sensor_id, "fs": pp.fs, "unit": "deg/h",
        "target": {"term": pp.term, "unit": UNITS[pp.term], "precision": pp.precision,
                   "level": pp.level,
                   "definition": "relative half-width (high - low) / (2 value) of the "
                                 "interval exp(log value +- z se), z = normal quantile"},
        "pilot": {"n": pp.pilot_n, "seconds": pp.pilot_n / pp.fs,
                  "terms": {t: {"value": e.value, "low": e.low, "high": e.high,
                                "unit": e.unit} for t, e in fit.terms.items()},
                  "model": list(pp.terms), "dropped_terms": list(pp.dropped_terms),
                  "taus_left_out": pp.taus_left_out, "tau_min": pp.tau_min,
                  "gof_p": fit.info["gof_p"], "half_width": pp.pilot_width,
                  "interval": "GLS, 90 %"},
        "plan": describe(pp.plan),
        "range": {"hours_low": _hours(pp.range_hours[0]),
                  "hours_high": _hours(pp.range_hours[1]),
                  "n_low": pp.range.n_low, "n_high": pp.range.n_high,
                  "params_low": {t: getattr(pp.range.params_low, t) for t in pp.terms},
                  "params_high": {t: getattr(pp.range.params_high, t) for t in TERMS
                                  if t in pp.terms or t in pp.assumed},
                  "assumed": pp.assumed,
                  "rule": "shortest and longest plan over the pilot's joint 90 % region of "
                          "the log values (fogbayes.plan.spread), the long end also with the "
                          "unresolved terms in 'assumed' at their 90 % upper bounds; null "
                          "hours = beyond max_days"},
        "ends": {"plans": ends,
                 "rule": "each model term in turn at the low and at the high end of its "
                         "pilot 90 % interval, the others at the estimate"},
        "method": "Fisher information of the octave AVAR estimates of the GLS fit "
                  "(fogbayes.plan.length): se(log term) = sqrt(diag((J' V^-1 J)^-1))",
    }


def plan_recording(rec, term: str, precision: float, *, level: float = 0.9,
                   max_days: float = MAX_DAYS, terms=TERMS) -> dict:
    """Plan from a :class:`~fogbayes.data.Recording` (rate on a uniform grid, gaps = NaN);
    ``terms``: the candidate terms of the pilot's model (default all five)."""
    from ..allan.workflow import uniform_rate

    y, fs, _ = uniform_rate(rec)
    pp = plan_from_pilot(y, fs, term, precision, level=level, max_days=max_days, terms=terms)
    return plan_document(pp, source=rec.meta.source, sensor_id=rec.meta.sensor_id)


def fmt_hours(h: float | None) -> str:
    """'3.2 h', '41 min', '12 d' or '> max' for None/inf."""
    if h is None or not math.isfinite(h):
        return "beyond max_days"
    if h < 0.99:
        return f"{h * 60:.3g} min"
    if h < 72.0:
        return f"{h:.3g} h"
    return f"{h:.4g} h ({h / 24:.3g} d)"


def _pct(x: float, digits: int = 3) -> str:
    return f"{100.0 * x:.{digits}g} %"


def summary_lines(doc: dict) -> list[str]:
    """A few lines for people: pilot estimate, planned length, range."""
    tg, pl, pi, rg = doc["target"], doc["plan"], doc["pilot"], doc["range"]
    t = tg["term"]
    e = pi["terms"][t]
    dropped = (f"; not resolved: {', '.join(pi['dropped_terms'])}" if pi["dropped_terms"]
               else "")
    out = [f"plan: pilot {fmt_hours(pi['seconds'] / 3600)} at {doc['fs']:g} Hz, model "
           f"{' '.join(pi['model'])}{dropped}",
           f"  pilot {t} = {e['value']:.4g} [{e['low']:.4g}, {e['high']:.4g}] {e['unit']} "
           f"(+-{_pct(pi['half_width'])} at {_pct(tg['level'])} from the pilot)",
           f"  record {fmt_hours(pl['hours'])} ({pl['n']} samples, {pl['seconds']:.0f} s) for "
           f"{t} to +-{_pct(tg['precision'])} at {_pct(tg['level'])} "
           f"(predicted +-{_pct(pl['half_width'], 4)})"]
    hi = rg["params_high"]
    lines_hi = ", ".join(f"{k} {v:.3g}" for k, v in hi.items() if k in ("N", "B", "K", "R"))
    extra = "".join(f"; {k} not resolved, taken <= {v:.3g}" for k, v in rg["assumed"].items())
    out.append(f"  range {fmt_hours(rg['hours_low'])} .. {fmt_hours(rg['hours_high'])} over the "
               f"pilot's 90 % uncertainty (longest at {lines_hi}{extra})")
    return out
