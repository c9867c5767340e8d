"""Compute what a calibration report shows, then hand it to the renderer.

``build_report`` is the one place that decides which analyses a report needs: it fits
(or takes a fit document), compensates, runs the Allan analysis on what is left and
collects the covariates for the residual plots. ``fogbayes.report`` only renders.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import FogbayesError
from . import workflow_for


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
                 allan: bool = True) -> Path:
    """Write the calibration report of ``rec`` to ``out`` and return its path.

    Args:
        model: fit this model first (``bias-t``, ``thermal``, ``composite``, ``allan``).
        fit: a fit document already computed (``fogbayes fit --json``); wins over ``model``.
        loop: a :class:`fogbayes.loop.LoopResult` whose story is told step by step.
    """
    from ..report import sections as S
    from ..report.html import write

    if fit is None and model is not None:
        fit = workflow_for(model).fit_recording(rec, model=model, bayes=bayes, seed=seed)
    parts, outliers, residual_rec = [], None, rec
    det = fit if fit is not None and fit.get("model") not in ("allan", "arma") else None
    if det is not None:
        cols = workflow_for(det["model"]).compensate_recording(rec, det)
        outliers = np.asarray(cols["outlier"], bool)
        if "rate" in cols:  # composite: the estimate of the input rate, deg/s
            if rec.input_rate is None:
                residual = None
            else:
                residual = (np.asarray(cols["rate"]) - rec.input_rate) * 3600.0
        else:
            residual = rec.replace(output=cols["output"]).rate("deg/h")
        if residual is not None:
            residual_rec = rec.replace(output=residual, unit="deg/h", scale_factor=None)
    parts.append(S.recording_section(rec, outliers=outliers))
    if det is not None:
        parts.append(S.model_section(det))
        if residual_rec is not rec:
            parts.append(S.residual_section(rec, residual_rec.output, covariates(rec)))
        if "metrics" in det:
            parts.append(S.stability_section(det))
        table = S.composite_table_section(det)
        if table is not None:
            parts.append(table)
    if loop is not None:
        from ..plot.loop import loop_section

        parts.append(loop_section(loop))
    allan_doc = fit if fit is not None and fit.get("model") == "allan" else None
    if allan_doc is None and allan:
        try:
            allan_doc = workflow_for("allan").fit_recording(residual_rec, model="allan", seed=seed)
        except FogbayesError as exc:
            parts.append(S.Section("Noise: Allan deviation").note(
                f"No Allan analysis for this record: {exc}", ok=False))
    if allan_doc is not None:
        sec = S.noise_section(allan_doc)
        if det is not None:
            sec.text("Computed on the residual after the fitted model, so that the thermal "
                     "drift does not hide the noise.")
        parts.append(sec)
    title = title or f"Calibration report: {rec.meta.sensor_id}"
    return write(out, title, parts, subtitle=f"source: {rec.meta.source or 'in memory'}")


def print_pdf(html_path: str | Path, pdf_path: str | Path) -> Path:
    """Print the HTML report to PDF with headless Chromium (needs the chromium package)."""
    import shutil
    import subprocess

    exe = shutil.which("chromium") or shutil.which("chromium-browser") or shutil.which("google-chrome")
    if exe is None:
        raise FogbayesError("PDF output needs headless Chromium, which is not installed",
                            column="--pdf", fix="apt-get install chromium, or open the HTML and print it")
    pdf_path = Path(pdf_path)
    subprocess.run([exe, "--headless", "--no-sandbox", "--disable-gpu", "--no-pdf-header-footer",
                    f"--print-to-pdf={pdf_path}", Path(html_path).resolve().as_uri()],
                   check=True, capture_output=True, timeout=300)
    return pdf_path
