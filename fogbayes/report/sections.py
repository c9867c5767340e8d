"""Report sections built from results that were already computed (renders only).

Each function takes a Recording and/or a result document (the JSON written by
``fogbayes fit``, ``fogbayes allan`` or ``fogbayes loop``) and returns a
:class:`~fogbayes.report.html.Section`. Nothing here fits or estimates anything.
"""

from __future__ import annotations

import numpy as np

from .html import Section


def recording_section(rec, *, outliers: np.ndarray | None = None) -> Section:
    """Summary table (duration, rate, temperatures, gaps, outliers) and time plots."""
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
        rows.append(["outliers flagged (3σ, kept in outputs)", int(np.sum(outliers))])
    sec = Section("Recording").table(["quantity", "value"], rows)
    if s.gaps:
        longest = max(s.gaps, key=lambda g: g.duration)
        sec.note(f"{len(s.gaps)} gap(s); the longest is {longest.duration:.4g} s at t = "
                 f"{longest.start:.6g} s. Gaps are kept as they are.", ok=False)
    return sec.figure(plot_recording(rec, outliers=outliers), caption="Output and temperature channels.")


def noise_section(doc: dict) -> Section:
    """ADEV with confidence bars, fitted terms and posterior band; the noise table."""
    from ..plot.allan import allan_figure

    sec = Section("Noise: Allan deviation")
    fit = doc.get("fit", {})
    sec.figure(allan_figure(doc), caption=f"Overlapping ADEV ({doc.get('ci', 0.9):.0%} intervals) "
                                          f"and the {fit.get('method', '')} fit of the five-term model.")
    rows = [[name, t.get("value"), t.get("low"), t.get("high"), t.get("unit"), t.get("present", True)]
            for name, t in fit.get("terms", {}).items()]
    sec.table(["term", "value", "low (90 %)", "high (90 %)", "unit", "present"], rows,
              caption="noise terms (canonical units)")
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
    raw = doc.get("params", {}).get("raw")
    if raw:
        se = raw.get("stderr") or [None] * len(raw["coef"])
        sec.table(["term", "coefficient", "std. error"],
                  [[t, c, e] for t, c, e in zip(raw["terms"], raw["coef"], se)],
                  caption="raw (papers' form) coefficients, for display and export")
    bayes = doc.get("bayes")
    if bayes:
        _posterior_tables(sec, bayes)
    fit = doc.get("fit")
    if isinstance(fit, dict):
        sec.table(["quantity", "value"], [[k, v] for k, v in fit.items()
                                          if isinstance(v, (int, float, bool, str))])
    return sec


def _posterior_tables(sec: Section, bayes: dict) -> None:
    conv = bayes.get("convergence", {})
    if conv:
        sec.table(["diagnostic", "value"], [[k, v] for k, v in conv.items()
                                            if isinstance(v, (int, float, bool, str))],
                  caption="sampler convergence (R-hat, ESS, divergences)")
    params = bayes.get("params") or bayes.get("coefficients")
    if isinstance(params, dict):
        rows = [[k, v.get("median"), v.get("low"), v.get("high")] for k, v in params.items()
                if isinstance(v, dict)]
        if rows:
            sec.table(["parameter", "median", "low", "high"], rows, caption="posterior intervals")


def residual_section(rec, residual: np.ndarray, covariates: dict[str, np.ndarray], *,
                     unit: str = "deg/h") -> Section:
    """Residual against time and against each covariate."""
    from ..plot.residuals import plot_residuals

    return Section("Residuals").figure(
        plot_residuals(rec.time, residual, covariates, unit=unit),
        caption="Residual after the fitted model against time (10 s means) and against each "
                "covariate (binned means, 95 % intervals that treat samples as independent).")


def stability_section(doc: dict) -> Section:
    """Bias stability before/after, full temperature range and per segment (paper 004)."""
    sec = Section("Compensation: bias stability before and after")
    metrics = doc.get("metrics", {})
    rows = []
    parts = [("full", metrics.get("full"))] + [
        (f"{s['kind']} {s['start_s']:.0f}–{s['stop_s']:.0f} s", s) for s in metrics.get("segments", [])]
    for label, part in parts:
        if not part:
            continue
        for r in part["stability"]:
            rows.append([label, r["window_s"], r["before"], r["after"], r["improvement_pct"]])
    sec.table(["segment", "window [s]", "before [deg/h]", "after [deg/h]", "improvement [%]"], rows)
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
