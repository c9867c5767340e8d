"""Report sections built from results that were already computed (renders only).

Each function takes a Recording and/or a result document (the JSON written by
``fogbayes fit``, ``fogbayes allan`` or ``fogbayes loop``) and returns a
:class:`~fogbayes.render.html.Section`. Nothing here fits or estimates anything.
"""

from __future__ import annotations

import numpy as np

from .html import Cell, Section, fmt, fmt_pct
from .labels import NOISE_TERMS, SEGMENTS, coefficient_unit, key_cell, quantity_rows, term_label


def gaussian_tail_fraction(n_sigma: float) -> float:
    """P(|Z| > n_sigma) for a standard normal Z: the share of a Gaussian record flagged."""
    from math import erfc, sqrt

    return erfc(n_sigma / sqrt(2.0))


def outlier_caption(n: int, flagged: int, gross: int | None, n_sigma: float = 3.0) -> str:
    """How many samples were flagged, against what Gaussian noise alone flags."""
    if not flagged:
        return "No sample flagged as an outlier."
    expect = gaussian_tail_fraction(n_sigma)
    s = (f"{flagged} samples ({fmt_pct(100.0 * flagged / n, decimals=2)}) lie beyond "
         f"{fmt(n_sigma)}σ of the fitted model; Gaussian noise alone puts "
         f"{fmt_pct(100.0 * expect, decimals=2)} there.")
    if gross is not None:
        s += (f" {gross} of them are gross errors (beyond 5 robust σ, red crosses); the others "
              "are the noise's own tail, drawn as small dots." if gross else
              " None is a gross error (beyond 5 robust σ): they are the noise's own tail, "
              "drawn as small dots.")
    return s + " Flagged samples are left out of the fit and kept in the outputs."


def recording_section(rec, *, outliers: np.ndarray | None = None,
                      gross: np.ndarray | None = None, n_sigma: float = 3.0) -> Section:
    """Summary table (duration, rate, temperatures, gaps, outliers) and time plots.

    ``outliers``: samples flagged by the n-sigma rule; ``gross``: the flagged samples that
    are gross errors (the figure emphasises only these; the rest are drawn small).
    """
    from ..plot.recording import plot_recording

    s = rec.sampling()
    rows = [["sensor", rec.meta.sensor_id], ["source", rec.meta.source or "in memory"],
            ["samples", rec.n], ["duration [h]", s.duration / 3600],
            ["sample rate [Hz]", s.sample_rate], ["irregular sampling", s.irregular],
            ["gaps (kept, never interpolated)", len(s.gaps)], ["output unit", rec.unit]]
    for j, name in enumerate(rec.temperature_names):
        col = rec.temperatures[:, j]
        rows.append([f"{name} [°C]", f"{col.min():.2f} … {col.max():.2f}"])
    if rec.input_rate is not None:
        rows.append(["input rate [°/s]", f"{rec.input_rate.min():.4g} … {rec.input_rate.max():.4g}"])
    if outliers is not None:
        rows.append([f"samples beyond {fmt(n_sigma)}σ (kept in outputs)", int(np.sum(outliers))])
    if gross is not None:
        rows.append(["gross errors (beyond 5 robust σ)", int(np.sum(gross))])
    sec = Section("Recording").table(["quantity", "value"], rows)
    if s.gaps:
        longest = max(s.gaps, key=lambda g: g.duration)
        sec.note(f"{len(s.gaps)} gap(s); the longest is {longest.duration:.4g} s at t = "
                 f"{longest.start:.6g} s. Gaps are kept as they are.", ok=False)
    cap = "Output and temperature channels against time."
    if outliers is not None:
        cap += " " + outlier_caption(rec.n, int(np.sum(outliers)),
                                     None if gross is None else int(np.sum(gross)), n_sigma)
    return sec.figure(plot_recording(rec, outliers=outliers, gross=gross), caption=cap)


def noise_section(doc: dict) -> Section:
    """ADEV with confidence bars, fitted terms and posterior band; the noise table."""
    from ..plot.allan import allan_figure

    sec = Section("Noise: Allan deviation")
    fit = doc.get("fit", {})
    sec.figure(allan_figure(doc), caption=f"Overlapping ADEV ({doc.get('ci', 0.9):.0%} intervals) "
                                          f"and the {fit.get('method', '')} fit of the five-term model.")
    lvl = f"{doc.get('ci', 0.9):.0%}"
    rows = [[Cell(NOISE_TERMS.get(name, name), title=f"JSON key: fit.terms.{name}"),
             t.get("value"), t.get("low"), t.get("high"), t.get("unit"),
             "yes" if t.get("present", True) else "no (an upper bound)"]
            for name, t in fit.get("terms", {}).items()]
    sec.table(["noise term", "value", f"low ({lvl})", f"high ({lvl})", "unit",
               "supported by the data"], rows,
              caption="Allan noise terms, canonical units; a term the data do not support is "
                      "reported by its interval, whose high end is an upper bound")
    if not doc.get("converged", True):
        sec.note("The noise fit did not converge: treat these numbers as unreliable.", ok=False)
    return sec


def model_section(doc: dict) -> Section:
    """Coefficients with standard errors and posterior intervals, convergence, warnings."""
    sec = Section(f"Fitted model: {doc.get('model')}")
    conv = doc.get("converged")
    sec.note("The fit converged." if conv else "The fit did NOT converge: do not use these "
             "coefficients without checking the diagnostics below.", ok=bool(conv))
    for w in doc.get("warnings", []):
        sec.note(w, ok=False)
    params = doc.get("params", {})
    raw = params.get("raw")
    bayes = doc.get("bayes")
    if raw and "coef" in raw:
        se = raw.get("stderr") or [None] * len(raw["coef"])
        basis = params.get("basis") or {}
        exps = basis.get("exponents") or [None] * len(raw["coef"])
        units = {k: coefficient_unit(e, basis.get("covariates", []), params.get("units"))
                 if e is not None else "" for k, e in zip(raw["terms"], exps)}
        braw = (bayes or {}).get("raw") or {}
        header = ["term", "coefficient", "std. error (LSQ)", "unit"]
        if braw.get("interval"):
            header[3:3] = ["posterior mean", f"{(bayes or {}).get('level', 0.9):.0%} interval"]
        rows = []
        for i, (t, c, e) in enumerate(zip(raw["terms"], raw["coef"], se)):
            row = [Cell(term_label(t), title=f"term {t}"), c, e, units[t]]
            if braw.get("interval"):
                lo, hi = braw["interval"][i]
                row[3:3] = [braw["mean"][i], Cell(f"[{fmt(lo)}, {fmt(hi)}]")]
            rows.append(row)
        sec.table(header, rows, caption="coefficients in the papers' raw form (bias = Σ coefficient "
                                        "× product of covariate powers, origin 0)")
    if doc.get("model") == "composite":
        from .composite import coefficient_table

        coefficient_table(sec, doc)
    if bayes:
        _posterior_tables(sec, bayes)
    fit = doc.get("fit")
    if isinstance(fit, dict):
        rows, notes = quantity_rows(fit)
        if rows:
            sec.table(["fit quantity", "value"], rows)
        for n in notes:
            sec.footnote(n[0].upper() + n[1:] + ".")
    return sec


def _posterior_tables(sec: Section, bayes: dict) -> None:
    conv = bayes.get("convergence", {})
    if conv:
        rows, _ = quantity_rows(conv)
        sec.table(["sampler diagnostic", "value"], rows,
                  caption="sampler convergence (R-hat, effective sample sizes, divergences)")
    params = bayes.get("params") or bayes.get("coefficients")
    if isinstance(params, dict):
        rows = [[key_cell(k), v.get("median"), v.get("low"), v.get("high")]
                for k, v in params.items() if isinstance(v, dict)]
        if rows:
            sec.table(["parameter", "median", "low", "high"], rows, caption="posterior intervals")


def residual_section(rec, residual: np.ndarray, covariates: dict[str, np.ndarray], *,
                     unit: str = "deg/h", model: str | None = None) -> Section:
    """Residual against time and against each covariate (in the model's colour)."""
    from ..plot.residuals import plot_residuals
    from ..plot.style import model_color

    who = f"the {model} model" if model else "the fitted model"
    return Section("Residuals").figure(
        plot_residuals(rec.time, residual, covariates, unit=unit,
                       color=model_color(model) if model else None),
        caption=f"Residual after {who} against time (10 s means) and against each "
                "covariate (binned means, 95 % intervals that treat samples as independent: "
                "with coloured noise they are too narrow, a guide for the eye). A model that "
                "explains its covariates leaves flat panels.")


MIN_MEANS_FOR_INTERVAL = 50  # fewer window means: no bootstrap interval is shown


def stability_section(doc: dict, intervals: dict | None = None) -> Section:
    """Bias stability before/after: whole record per window, then per segment (paper 004).

    ``intervals``: window (s) -> :class:`fogbayes.render.bootstrap.StabilityInterval` of
    the whole record (computed by the caller); shown where they rest on at least
    ``MIN_MEANS_FOR_INTERVAL`` window means.
    """
    sec = Section("Compensation: bias stability before and after")
    metrics = doc.get("metrics", {})
    full = metrics.get("full")
    intervals = intervals or {}
    if full:
        rows, lvl = [], None
        for r in full["stability"]:
            iv = intervals.get(float(r["window_s"]))
            if iv is not None and iv.n_means >= MIN_MEANS_FOR_INTERVAL:
                lvl = iv.level
                ci = [Cell(f"[{fmt(iv.before.low)}, {fmt(iv.before.high)}]"),
                      Cell(f"[{fmt(iv.after.low)}, {fmt(iv.after.high)}]"),
                      Cell(f"[{fmt(iv.improvement_pct.low, sig=3)}, {fmt(iv.improvement_pct.high, sig=3)}]")]
            else:
                ci = [None, None, None]
            rows.append([r["window_s"], r["before"], ci[0], r["after"], ci[1],
                         Cell(fmt_pct(r["improvement_pct"])), ci[2]])
        name = f"{lvl:.0%} interval" if lvl else "interval"
        sec.table(["window [s]", "before [deg/h]", name, "after [deg/h]", name,
                   "improvement", f"{name} [%]"], rows,
                  caption="whole record; intervals from the block bootstrap of the headline "
                          f"(— where fewer than {MIN_MEANS_FOR_INTERVAL} window means)")
        b0, b1 = full.get("bias_before"), full.get("bias_after")
        if b0 is not None and b1 is not None:
            # a least-squares fit with a constant leaves a mean of 0 up to rounding
            floor = 1e-9 * max(abs(b0), full["stability"][0]["before"] if full["stability"] else 0.0, 1e-300)
            sec.table(["", "before", "after"],
                      [[Cell("bias B0, mean rate [deg/h]", title="JSON keys: bias_before, bias_after"),
                        b0, Cell(fmt(b1, floor=floor))]])
    segs = metrics.get("segments", [])
    if segs:
        windows = [r["window_s"] for r in segs[0]["stability"]]
        rows = []
        for s in segs:
            by_w = {r["window_s"]: r for r in s["stability"]}
            lab = (f"{SEGMENTS.get(s['kind'], s['kind'])}, "
                   f"{s['start_s'] / 3600:.2f}–{s['stop_s'] / 3600:.2f} h")
            row = [Cell(lab, title=f"{s['kind']} {s['start_s']:.0f}–{s['stop_s']:.0f} s")]
            for w in windows:
                r = by_w.get(w)
                row.append(Cell(f"{fmt(r['before'])} → {fmt(r['after'])} ({fmt_pct(r['improvement_pct'])})")
                           if r else None)
            rows.append(row)
        sec.table(["segment", *[f"{fmt(w)} s: before → after [deg/h] (improvement)" for w in windows]],
                  rows, caption="per segment of the temperature profile (no intervals: "
                                "segments are short)")
    return sec


def composite_table_section(doc: dict) -> Section | None:
    """Paper 000 style table: relative error per temperature and rate, before and after."""
    table = doc.get("tables") or doc.get("before_after")
    if not isinstance(table, dict) or "temperatures" not in table:
        return None
    sec = Section("Relative error per temperature and rate (paper 000 layout)")
    temps, rates = table["temperatures"], table["rates"]
    for key in ("before", "after"):
        if key in table:
            sec.table(["T [°C] \\ Ω [°/s]", *rates],
                      [[t, *row] for t, row in zip(temps, table[key])],
                      caption=f"relative error [%], {key} compensation")
    return sec
