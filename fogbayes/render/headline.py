"""The headline block a report opens with: what was calibrated, the model, the answer.

The reader who receives a report first wants: which sensor and file, over what span and
temperatures; which model; bias stability before -> after with its uncertainty, the
improvement with its uncertainty; and a one-line verdict. This module renders that block
from numbers already computed (:mod:`fogbayes.render.bootstrap` intervals); the
``<span>`` classes (``bs before``, ``ci before-ci``, ...) are what tests read back.
"""

from __future__ import annotations

import html
from pathlib import Path
from typing import Sequence

import numpy as np

from .bootstrap import StabilityInterval, StdInterval
from .html import Section, fmt, fmt_pct

HEADLINE_TITLE = "Result"


def recording_line(rec) -> str:
    """HTML: sensor · file · span · samples · temperature range (user text escaped)."""
    s = rec.sampling()
    src = rec.meta.source
    parts = [f"sensor <b>{html.escape(str(rec.meta.sensor_id))}</b>"]
    parts.append(f"file <code title=\"{html.escape(str(src), quote=True)}\">"
                 f"{html.escape(Path(src).name)}</code>" if src else "recording in memory")
    hours = s.duration / 3600.0
    span = f"{hours:.2f} h" if hours >= 0.5 else f"{s.duration / 60.0:.1f} min"
    parts.append(f"{span} at {fmt(s.sample_rate)} Hz ({rec.n} samples"
                 f"{f', {len(s.gaps)} gaps' if s.gaps else ''})")
    if rec.has_temperature:
        t = rec.temperature
        parts.append(f"temperature {np.nanmin(t):.1f} … {np.nanmax(t):.1f} °C")
    if rec.input_rate is not None:
        w = rec.input_rate
        parts.append(f"input rate {fmt(np.nanmin(w))} … {fmt(np.nanmax(w))} °/s")
    return " · ".join(parts)


def model_line(doc: dict | None) -> str:
    """Plain text: the model a fit document holds, in words."""
    if not doc:
        return "none fitted (the recording and its noise only)"
    m = doc.get("model")
    spec = (doc.get("params") or {}).get("spec") or {}
    terms = ((doc.get("params") or {}).get("basis") or {}).get("terms") or []
    n = f", {len(terms)} coefficients" if terms else ""
    if m == "bias-t":
        return (f"bias-t: bias = polynomial of order {spec.get('t_order', '?')} in temperature"
                f"{n}, least squares on {fmt(doc.get('processing', {}).get('average_s', 1.0))} s means")
    if m == "thermal":
        rate = spec.get("rate_order", 0)
        return (f"thermal (paper 004): bias = polynomial of order {spec.get('t_order', '?')} in "
                f"temperature T + order {rate} in its rate dT/dt{n}, least squares on "
                f"{fmt(doc.get('processing', {}).get('average_s', 1.0))} s means")
    if m == "composite":
        o = doc.get("orders", {}).get("label", "")
        return f"composite (paper 000): scale factor and bias in temperature and rate, orders {o}"
    if m == "allan":
        return "five-term Allan-variance noise model (Q, N, B, K, R); no compensation"
    return str(m)


def _input(doc: dict) -> dict:
    """Where a document says it was computed: a noise document's ``source``, ``n`` and
    ``sensor_id``, or a fit document's ``input`` block (the same keys)."""
    if "source" not in doc and isinstance(doc.get("input"), dict):
        return doc["input"]
    return doc


def _same_recording(doc: dict, rec) -> bool:
    """Whether a document was computed from ``rec``: the same file (resolved path), or a
    file of the same name and sample count (the path as given may be relative)."""
    doc = _input(doc)
    src, here = doc.get("source"), rec.meta.source
    if not isinstance(src, str) or not src or not here:
        return False
    try:
        if Path(src).resolve() == Path(here).resolve():
            return True
    except (OSError, RuntimeError):
        pass
    return Path(src).name == Path(here).name and doc.get("n") == rec.n


def noise_origin(doc: dict, doc_path: str | None, rec,
                 what: str = "noise analysis") -> str | None:
    """Plain text: where the numbers of a document handed to the report come from, when
    that is not ``rec`` itself (None when it is: the numbers are this recording's).

    ``"from adev.json, the noise analysis of static.csv (sensor 0070), not of this
    recording"``; ``what="fit"`` for a fit document's coefficients. A reader must never
    take another recording's N and B, or another run's fit, for this one's.
    """
    if _same_recording(doc, rec):
        return None
    name = Path(doc_path).name if doc_path else f"the {what} document given"
    doc = _input(doc)
    src = doc.get("source")
    of = Path(src).name if isinstance(src, str) and src else "another recording"
    sensor = doc.get("sensor_id")
    if sensor not in (None, "") and str(sensor) != str(rec.meta.sensor_id):
        of += f" (sensor {sensor})"
    return f"from {name}, the {what} of {of}, not of this recording"


def _cells(iv, pct: bool, role: str) -> str:
    f = fmt_pct if pct else fmt
    point = f(iv.value)
    lo, hi = (fmt(iv.low, sig=3), fmt(iv.high, sig=3)) if pct else (fmt(iv.low), fmt(iv.high))
    unit = " %" if pct else ""
    return (f'<td><span class="bs {role}">{html.escape(point)}</span> '
            f'<span class="ci {role}-ci">[{html.escape(lo)}, {html.escape(hi)}]{unit}</span></td>')


def stability_table(rows: Sequence[tuple[str, str, StabilityInterval]], *, unit: str = "deg/h") -> str:
    """HTML table: one row per (label, title, interval): before, after, improvement."""
    if not rows:
        return ""
    w = rows[0][2].window_s
    lvl = rows[0][2].level
    head = (f"<tr><th>bias stability, {fmt(w)} s means</th><th>before [{unit}]</th><th></th>"
            f"<th>after [{unit}]</th><th>improvement</th></tr>")
    body = []
    for i, (lab, title, si) in enumerate(rows):
        t = f' title="{html.escape(title, quote=True)}"' if title else ""
        body.append(f'<tr class="{"result main" if i == 0 else "result"}"><td{t}>'
                    f"{html.escape(lab)}</td>{_cells(si.before, False, 'before')}"
                    f"<td>→</td>{_cells(si.after, False, 'after')}"
                    f"{_cells(si.improvement_pct, True, 'improvement')}</tr>")
    cap = (f"<caption>point value, then its {lvl:.0%} interval [low, high]¹; improvement = "
           f"100 (before − after) / before</caption>")
    return f'<table class="headline-table">{cap}<thead>{head}</thead><tbody>{"".join(body)}</tbody></table>'


def improvement_verdict(si: StabilityInterval, what: str) -> tuple[str, bool]:
    """One sentence on an improvement interval, and whether it is good news."""
    imp = si.improvement_pct
    pct = f"{fmt_pct(imp.value)} ({si.level:.0%} interval {fmt(imp.low, sig=3)} … {fmt(imp.high, sig=3)} %)"
    ba = f"{fmt(si.before.value)} → {fmt(si.after.value)} deg/h"
    if imp.low > 0:
        return f"{what} lowers the {fmt(si.window_s)} s bias stability by {pct}: {ba}.", True
    if imp.high < 0:
        return (f"{what} makes the {fmt(si.window_s)} s bias stability worse by "
                f"{fmt_pct(-imp.value)}: {ba}.", False)
    return (f"{what}: no change this record can resolve ({ba}; improvement {pct} includes 0).",
            False)


def single_html(si: StdInterval, unit: str = "deg/h") -> str:
    """One bias stability (no compensation) with its interval."""
    v = si.value
    return (f'<p class="what"><b>Bias stability</b> ({fmt(si.window_s)} s means): '
            f'<span class="bs value">{html.escape(fmt(v.value))}</span> {unit} '
            f'<span class="ci value-ci">[{html.escape(fmt(v.low))}, {html.escape(fmt(v.high))}]'
            f' {unit}, {si.level:.0%} interval¹</span></p>')


def headline_section(rec, *, model: str, rows: Sequence[tuple[str, str, StabilityInterval]] = (),
                     verdict: str = "", ok: bool | None = None, notes: Sequence[str] = (),
                     extra_html: str = "", single: StdInterval | None = None,
                     what: str | None = None) -> Section:
    """The first section of every report (see module doc).

    ``rows``: (label, tooltip, interval) of before -> after comparisons, the main one first;
    ``single``: a bias stability without compensation; ``what``: HTML replacing the
    recording line (when no Recording is at hand).
    """
    sec = Section(HEADLINE_TITLE, lead=True)
    sec.html(f'<p class="what"><b>Calibrated:</b> {what if what is not None else recording_line(rec)}</p>')
    sec.html(f'<p class="what"><b>Model:</b> {html.escape(model)}</p>')
    if rows:
        sec.html(stability_table(rows))
    if single is not None:
        sec.html(single_html(single))
    if extra_html:
        sec.html(extra_html)
    if verdict:
        cls = "verdict" + ("" if ok is None else (" good" if ok else " caution"))
        sec.html(f'<p class="{cls}"><b>Verdict:</b> {html.escape(verdict)}</p>')
    for n in notes:
        sec.note(n, ok=False)
    first = rows[0][2] if rows else single
    if first is not None:
        sec.footnote("¹ " + first.method() + " Bias stability is paper 004's eq. 13: the "
                     "standard deviation of the rate averaged over consecutive "
                     f"{fmt(first.window_s)} s windows.")
    return sec
