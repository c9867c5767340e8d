"""The pool report: population of a sensor type, each unit alone and pooled, outliers."""

from __future__ import annotations

from pathlib import Path

from .html import Section, fmt, figure_html, write
from .labels import interval_text, unit_text


def bound_text(b: dict) -> str:
    """An upper bound as the reports show it: ``< 0.026 (95 %)``."""
    return f"< {fmt(b['upper'], sig=2)} ({b['level'] * 100:g} %)"


def _population_rows(pool: dict) -> list[list]:
    rows = []
    for t in pool["terms"]:
        p = pool["population"][t]
        if not p.get("resolved", True):  # an upper bound only: no median, interval, spread
            ev = p["evidence"]
            rows.append([t, unit_text(p["median"]["unit"]), bound_text(p["median"]),
                         f"not resolved: the records do not exclude {t} = 0 in every unit "
                         f"(χ² {fmt(ev['chi2_absent'], sig=2)} < {fmt(ev['threshold'], sig=3)})",
                         "—", "—", bound_text(p["new_unit"])])
            continue
        med, f, new = p["median"], p["spread"]["factor"], p["new_unit"]
        rows.append([t, unit_text(med["unit"]), fmt(med["value"]),
                     interval_text(med["low"], med["high"]),
                     f"×{fmt(f['value'], sig=3)}", f"[×{fmt(f['low'], sig=3)}, ×{fmt(f['high'], sig=3)}]",
                     interval_text(new["low"], new["high"])])
    return rows


def _unit_rows(pool: dict) -> list[list]:
    rows = []
    for u in pool["units"]:
        row = [u["name"]]
        for t in pool["terms"]:
            s, p = u["terms"][t]["single"], u["terms"][t]["pooled"]
            # an unresolved term: its upper bound, never a value with an interval
            alone = (f"{fmt(s['value'])} {interval_text(s['low'], s['high'])}" if s["resolved"]
                     else f"< {fmt(s['high'], sig=2)} (95 %)")
            pooled = (bound_text(p) if "upper" in p
                      else f"{fmt(p['value'])} {interval_text(p['low'], p['high'])}")
            row += [alone, pooled]
        o = u["outlier"]
        row += [fmt(o["p"], sig=2), "yes" if o["flagged"] else "no", u["taus_left_out"]]
        rows.append(row)
    return rows


def pool_sections(name: str | None, pool: dict) -> list[Section]:
    from ..plot.pool import pool_figure

    where = "" if name is None else f" — {name}"
    head = Section(f"Population{where}", lead=name is None)
    n = len(pool["units"])
    head.text(f"{n} units pooled by a hierarchical model of their log noise terms: the "
              "population median is the typical unit, the spread factor is how much units "
              "differ (one log standard deviation), and a new unit of this type falls in the "
              "last column's range with 90 % probability. A term whose absence the units' "
              "records do not exclude is shown as an upper bound (95 %) only.")
    head.table(["term", "unit", "population median", "90 % interval", "between-unit spread",
                "90 % interval", "a new unit (90 %)"], _population_rows(pool))
    if pool.get("prior"):
        pr = pool["prior"]
        sheet = ", ".join(f"{t} {fmt(v['value'])} {unit_text(v['unit'])} (×/÷ {fmt(v['looseness'], sig=3)})"
                          for t, v in pr["terms"].items() if t in pool["terms"])
        head.text(f"Datasheet prior on the typical unit{' (' + pr['sensor'] + ')' if pr.get('sensor') else ''}: "
                  f"{sheet or 'none of the pooled terms'}.")
    if pool["flagged"]:
        head.note(f"Outside the population (p < {pool['flag_level']:g}): "
                  f"{', '.join(pool['flagged'])}.", ok=False)
    else:
        head.note(f"No unit lies outside the population (every leave-one-out p ≥ "
                  f"{pool['flag_level']:g}).")
    if not pool["converged"]:
        head.note("The sampler did not meet its convergence rule (R-hat < 1.01, ESS > 200, "
                  "no divergences): treat the intervals as rough.", ok=False)
    for w in pool["warnings"]:
        head.note(w, ok=False)
    units = Section(f"Units alone and pooled{where}")
    units.html(figure_html(pool_figure(pool, title=name or ""),
                           caption="Grey: each unit's own 90 % interval (a left arrow: not "
                                   "resolved, an upper bound); colour: pooled (red: flagged); "
                                   "band: population median (hatched from the edge: only "
                                   "its 95 % bound, not resolved); dashed: a new unit's 90 % "
                                   "range."))
    header = ["unit"]
    for t in pool["terms"]:
        header += [f"{t} alone", f"{t} pooled"]
    units.table(header + ["outlier p", "flagged", "taus left out"], _unit_rows(pool))
    d = pool["diagnostics"]
    units.details("Method", pool["method"] + ".",
                  f"Sampler: R-hat max {fmt(d['r_hat_max'], sig=4)}, ESS min "
                  f"{fmt(d['ess_min'], sig=3)}, {d['divergences']} divergences; leave-one-out "
                  f"refits {d['refits']} ({d['refits_converged']} converged), the other units by "
                  "Pareto-smoothed importance sampling.")
    return [head, units]


def write_pool_report(doc: dict, out: str | Path) -> Path:
    sections = []
    channels = doc["channels"]
    single = len(channels) == 1
    for name, pool in channels.items():
        sections += pool_sections(None if single else name, pool)
    title = f"Noise of a population: {len(next(iter(channels.values()))['units'])} units"
    return write(out, title, sections, subtitle=f"model {doc['model']}, fogbayes.pool/1")
