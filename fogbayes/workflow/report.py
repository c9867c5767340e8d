"""Compute what a calibration report shows, then hand it to :mod:`fogbayes.render`.

``build_report`` fits (or takes a document), compensates, runs the Allan analysis, separates
gross errors (:func:`gross_errors`) and computes the headline's bootstrap intervals
(:mod:`fogbayes.render.bootstrap`, :mod:`fogbayes.render.headline`). :func:`report` is
``fogbayes.report(...)``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from ..errors import FogbayesError
from . import workflow_for


def report(rec, fit: dict | str | Path | None = None, out: str | Path = "report.html", *,
           model: str | None = None, loop=None, bayes: bool = False, seed: int = 0,
           title: str | None = None, allan: bool = True, pdf: str | Path | None = None) -> Path:
    """Write the self-contained HTML report of ``rec`` to ``out`` and return its path.

    Args:
        rec: a :class:`~fogbayes.data.Recording`, or the path of a recording file (read
            with the defaults of :func:`fogbayes.load`).
        fit: a fit document (``fogbayes.fit`` / ``fogbayes fit --json``), a loop document
            (``fogbayes loop --json``: its calibration applied to ``rec``), a multi-axis
            noise document, or the path of one; validated as ``fogbayes report --fit`` does.
        model: fit this model first when ``fit`` is None (``bias-t``, ``thermal``,
            ``composite``, ``allan``); with ``bayes`` its posterior intervals.
        loop: a :class:`fogbayes.loop.LoopResult` (``fogbayes.run_loop``) told step by step.
        allan: add the Allan analysis of what the model leaves (default on).
        pdf: also print the report to this PDF (headless Chromium).

    Raises the errors ``fogbayes report`` turns into one line: a
    :class:`~fogbayes.errors.FogbayesError` naming the document or recording and the fix.
    """
    if isinstance(rec, (str, Path)):
        from ..data import load

        rec = load(rec)
    doc: Any = fit
    if isinstance(fit, (str, Path)):
        from ..data.documents import read_calibration

        doc = read_calibration(fit)
    elif isinstance(fit, dict):
        from ..data.axes_doc import is_axes_document
        from ..data.doc_rules import is_loop_document
        from ..support.jsonable import to_jsonable

        doc = to_jsonable(fit)
        if is_loop_document(doc):
            from ..loop.calibration_doc import validate_loop_document

            doc = validate_loop_document(doc)
        elif not is_axes_document(doc):
            from ..data.documents import validate_in_memory

            validate_in_memory(doc)
    path = build_report(rec, out, model=model, fit=doc, loop=loop, bayes=bayes, seed=seed,
                        title=title, allan=allan,
                        fit_source=str(fit) if isinstance(fit, (str, Path)) else None)
    if pdf is not None:
        print_pdf(path, pdf)
    return path


def covariates(rec) -> dict[str, np.ndarray]:
    """Covariates a residual is plotted against: temperatures, dT/dt, input rate."""
    from ..preprocess.temperature_rate import temperature_rate_per_min

    out = {}
    for j, name in enumerate(rec.temperature_names):
        out[f"{name} [°C]"] = rec.temperatures[:, j]
    if rec.has_temperature and rec.n > 20:
        try:
            out["dT/dt [°C/min]"] = temperature_rate_per_min(rec.time, rec.temperature, method="savgol",
                                                             window_s=min(600.0, rec.sampling().duration / 4))
        except FogbayesError:
            pass  # too short or too gappy for a smoothed derivative: the panel is left out
    if rec.input_rate is not None:
        out["input rate [°/s]"] = rec.input_rate
    return out


def build_report(rec, out: str | Path, *, model: str | None = None, fit: dict | None = None,
                 loop=None, bayes: bool = False, seed: int = 0, title: str | None = None,
                 allan: bool = True, fit_source: str | None = None) -> Path:
    """Write the calibration report of ``rec`` to ``out`` and return its path.

    Args:
        model: fit this model first (``bias-t``, ``thermal``, ``composite``, ``allan``).
        fit: a fit document already computed (``fogbayes fit --json``); wins over ``model``.
        loop: a :class:`fogbayes.loop.LoopResult` whose story is told step by step.
        fit_source: the file ``fit`` was read from; the noise numbers of a noise document
            are quoted with it, and with the recording they were computed from when that is
            not ``rec`` (:func:`fogbayes.render.headline.noise_origin`).
    """
    from ..render import sections as S
    from ..render.html import write

    from ..data.doc_rules import is_loop_document

    if fit is not None and is_loop_document(fit):
        return _loop_calibration_report(rec, out, fit, seed=seed, title=title, allan=allan)
    from ..data.axes_doc import is_axes_document

    if fit is not None and is_axes_document(fit):
        return _axes_report(rec, out, fit, title=title, fit_source=fit_source)
    given = fit is not None  # a document handed in (not fitted here): its origin is named
    if fit is None and model is not None:
        fit = workflow_for(model).fit_recording(rec, model=model, bayes=bayes, seed=seed)
    parts, outliers, gross, residual_rec = [], None, None, rec
    det = fit if fit is not None and fit.get("model") not in ("allan", "arma") else None
    residual = None
    if det is not None:
        cols = workflow_for(det["model"]).compensate_recording(rec, det)
        outliers = np.asarray(cols["outlier"], bool)
        if "rate" in cols:  # composite: the estimate of the input rate, deg/s
            if rec.input_rate is not None:
                residual = (np.asarray(cols["rate"]) - rec.input_rate) * 3600.0
        else:
            residual = rec.replace(output=cols["output"]).rate("deg/h")
        if residual is not None:
            residual_rec = rec.replace(output=residual, unit="deg/h", scale_factor=None)
            gross = gross_errors(residual, outliers)
    n_sigma = float((det or {}).get("processing", {}).get("n_sigma", 3.0))
    intervals = {}
    if det is not None and "metrics" in det and residual is not None:
        intervals = _intervals(rec, residual, det)
    parts.append(_headline(rec, det, fit, loop, intervals, residual_rec, seed,
                           fit_source if given else None, given))
    parts.append(S.recording_section(rec, outliers=outliers, gross=gross, n_sigma=n_sigma))
    if det is not None:
        parts.append(S.model_section(det))
        if residual_rec is not rec:
            parts.append(S.residual_section(rec, residual_rec.output, covariates(rec),
                                            model=det.get("model")))
        if "metrics" in det:
            parts.append(S.stability_section(det, intervals))
        table = S.composite_table_section(det)
        if table is not None:
            parts.append(table)
    if loop is not None:
        from ..render.loop import loop_section

        parts.append(loop_section(loop))
    allan_doc = fit if fit is not None and fit.get("model") == "allan" else None
    given_noise = given and allan_doc is not None  # quoted from a document
    if allan_doc is None and allan:
        try:
            allan_doc = workflow_for("allan").fit_recording(residual_rec, model="allan", seed=seed)
        except FogbayesError as exc:
            parts.append(S.Section("Noise: Allan deviation").note(
                f"No Allan analysis for this record: {exc}", ok=False))
    if allan_doc is not None:
        sec = S.noise_section(allan_doc)
        origin = _noise_origin(allan_doc, fit_source, rec) if given_noise else None
        if origin:
            sec.text(f"The noise shown is {origin}.")
        elif det is not None:
            sec.text("Computed on the residual after the fitted model, so that the thermal "
                     "drift does not hide the noise.")
        parts.append(sec)
    title = title or f"Calibration report: {rec.meta.sensor_id}"
    return write(out, title, parts, subtitle=f"source: {rec.meta.source or 'in memory'}")


def _axes_report(rec, out, doc: dict, *, title, fit_source=None) -> Path:
    """A multi-axis noise document: the recording, then one noise section per axis."""
    from ..render import sections as S
    from ..render.html import write

    if doc["model"] != "allan":
        raise FogbayesError(f"a multi-axis {doc['model']!r} document has no report yet",
                            column="--fit", fix="report each axis with its own document")
    parts = [S.recording_section(rec)]
    for name, sub in doc["axes"].items():
        sec = S.noise_section(sub)
        sec.title = f"Noise: Allan deviation, axis {name}"
        origin = _noise_origin(sub, fit_source, rec)
        if origin:
            sec.text(f"The noise shown is {origin}.")
        parts.append(sec)
    title = title or f"Noise report: {rec.meta.sensor_id}, axes {', '.join(doc['axes'])}"
    return write(out, title, parts, subtitle=f"source: {rec.meta.source or 'in memory'}")


GROSS_SIGMA = 5.0  # a Gaussian sample lies beyond 5 sigma once in 1.7 million


def gross_errors(residual: np.ndarray, flagged: np.ndarray, k: float = GROSS_SIGMA) -> np.ndarray:
    """The flagged samples that are gross errors: beyond ``k`` robust sigma of the residual.

    The n-sigma rule (3 sigma) also flags the noise's own tail, 0.27 % of a Gaussian record;
    only samples beyond ``k`` robust sigma (1.4826 MAD around the median) are errors worth
    pointing at.
    """
    r = np.asarray(residual, float)
    ok = np.isfinite(r)
    if not ok.any():
        return np.asarray(flagged, bool)
    med = np.median(r[ok])
    sigma = 1.4826 * np.median(np.abs(r[ok] - med))
    far = ~ok | (np.abs(r - med) > k * sigma) if sigma > 0 else ~ok
    return np.asarray(flagged, bool) & far


def _loop_calibration_report(rec, out, doc, *, seed, title, allan) -> Path:
    """A loop document's calibration applied to ``rec``: headline, what was applied,
    recording, residual, noise of the calibrated output."""
    from ..render import calibration as C
    from ..render import sections as S
    from ..render.html import write

    applied, residual = C.apply_loop_document(rec, doc)
    outliers = np.asarray(applied.columns["outlier"], bool)
    parts = [C.calibration_headline(rec, doc, residual, seed),
             C.calibration_section(doc, applied),
             S.recording_section(rec, outliers=outliers)]
    residual_rec = rec
    if residual is not None:
        residual_rec = rec.replace(output=residual, unit="deg/h", scale_factor=None)
        parts.append(S.residual_section(rec, residual, covariates(rec), model=doc["model"]))
    if allan:
        try:
            parts.append(S.noise_section(workflow_for("allan").fit_recording(
                residual_rec, model="allan", seed=seed)))
        except FogbayesError as exc:
            parts.append(S.Section("Noise: Allan deviation").note(
                f"No Allan analysis for this record: {exc}", ok=False))
    return write(out, title or f"Calibration report: {rec.meta.sensor_id}", parts,
                 subtitle=f"source: {rec.meta.source or 'in memory'}; calibration: the loop "
                          f"document of {doc['input'].get('file') or 'another run'}")


def _intervals(rec, residual, det) -> dict:
    """Window (s) -> bootstrap StabilityInterval of the whole record, raw vs compensated."""
    from ..render.bootstrap import stability_intervals

    out = {}
    for row in det["metrics"].get("full", {}).get("stability", []):
        w = float(row["window_s"])
        try:
            out[w] = stability_intervals(rec.rate("deg/h"), {"after": residual}, rec.time,
                                         window_s=w)["after"]
        except (ValueError, FogbayesError):
            continue  # fewer than three window means
    return out


def _noise_origin(doc, fit_source, rec, what: str = "noise analysis") -> str | None:
    from ..render.headline import noise_origin

    return noise_origin(doc, fit_source, rec, what)


def _headline(rec, det, fit, loop, intervals, residual_rec, seed, fit_source=None,
              given=False):
    """The headline section: the model fitted, the loop, or the noise alone; a document
    handed in (``given``) is named with the recording it was fitted on."""
    from ..render.headline import headline_section, improvement_verdict
    from ..render.headline import model_line as _line

    def model_line(doc):
        origin = _noise_origin(doc, fit_source, rec, "fit") if given and doc is det else None
        return f"{_line(doc)}; {origin}" if origin else _line(doc)

    if det is not None and intervals:
        si = intervals[min(intervals)]
        m = det.get("model")
        verdict, ok = improvement_verdict(si, f"Compensation with {m}")
        notes = [] if det.get("converged", True) else [
            "The fit did not converge: do not use these coefficients (see the model section)."]
        return headline_section(rec, model=model_line(det),
                                rows=[(f"raw → compensated ({m})", "", si)],
                                verdict=verdict, ok=ok and det.get("converged", True), notes=notes)
    if det is not None and "metrics" in det:
        return headline_section(rec, model=model_line(det), verdict="The record is too short "
                                "for a bias stability with an interval (fewer than three "
                                "1 s windows).", ok=False)
    if det is not None:  # composite: the relative rate error of the calibration table
        return _composite_headline(rec, det, model_line(det))
    if loop is not None:
        from ..render.loop import loop_headline

        return loop_headline(loop, rec)
    from ..render.bootstrap import single_stability

    try:
        single = single_stability(residual_rec.rate("deg/h"), residual_rec.time)
    except (ValueError, FogbayesError):
        single = None
    verdict = "Noise only: no compensation model was fitted"
    if fit is not None and fit.get("model") == "allan":
        terms = fit.get("fit", {}).get("terms", {})
        bits = [f"{k} = {_fmt(t.get('value'))} [{_fmt(t.get('low'))}, {_fmt(t.get('high'))}] "
                f"{t.get('unit', '')}" for k, t in terms.items() if k in ("N", "B") and t]
        if bits:
            verdict += "; " + ", ".join(bits)
            origin = _noise_origin(fit, fit_source, rec) if given else None
            if origin:
                verdict += f" {origin}"
    return headline_section(rec, model=model_line(fit), single=single, verdict=verdict + ".")


def _fmt(v):
    from ..render.html import fmt

    return fmt(v)


def _composite_headline(rec, det, model: str):
    from ..render.composite import error_verdict
    from ..render.headline import headline_section

    table = det.get("table")
    verdict, ok = "", None
    if isinstance(table, list) and table and "before_error_pct" in table[0]:
        verdict, ok = error_verdict(table)
    return headline_section(rec, model=model, verdict=verdict or
                            "see the model section for the calibrated coefficients.", ok=ok)


def print_pdf(html_path: str | Path, pdf_path: str | Path) -> Path:
    """Print the HTML report to PDF with headless Chromium (needs the chromium package)."""
    import shutil
    import subprocess

    exe = shutil.which("chromium") or shutil.which("chromium-browser") or shutil.which("google-chrome")
    if exe is None:
        raise FogbayesError("PDF output needs headless Chromium, which is not installed",
                            column="--pdf", fix="apt-get install chromium, or open the HTML and print it")
    from ..data.atomic import atomic_path

    pdf_path = Path(pdf_path)
    with atomic_path(pdf_path) as tmp:  # Chromium writes a temporary file, renamed when whole
        subprocess.run([exe, "--headless", "--no-sandbox", "--disable-gpu",
                        "--no-pdf-header-footer", f"--print-to-pdf={tmp.resolve()}",
                        Path(html_path).resolve().as_uri()],
                       check=True, capture_output=True, timeout=300)
    return pdf_path
