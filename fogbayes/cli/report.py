"""``fogbayes report REC``: one self-contained HTML calibration report."""

from __future__ import annotations

from pathlib import Path

import typer

from ..errors import FileFormatError
from ._app import app
from ._common import (QUIET_OPT, REC_ARG, TIME_UNIT_OPT, load_recording, progress,
                      reading_options, refuse_overwrite, say)


def _read_json(path: Path, what: str) -> dict:
    """The JSON object at ``path``; one line naming the file if unreadable or not an object."""
    from ..data.json_file import read_json_file

    fix = f"pass the file written by 'fogbayes {what} --json'"
    doc = read_json_file(path, f"the {what} JSON", fix, error=FileFormatError)
    if not isinstance(doc, dict):
        raise FileFormatError(f"the {what} JSON is a {type(doc).__name__}, not an object with "
                              "fields", file=str(path), fix=fix)
    from ..data.doc_kinds import refuse_other_kind

    refuse_other_kind(doc, str(path), (f"{what} document", {what}, fix), error=FileFormatError)
    return doc


@app.command()
def report(
    rec_path: Path = REC_ARG,
    out: Path = typer.Option(Path("report.html"), "--out", "-o", help="HTML file to write."),
    model: str = typer.Option(None, "--model", "-m",
                              help="Fit this model first: bias-t, thermal, composite, allan."),
    fit: Path = typer.Option(None, "--fit", "--params", "-p",
                             help="Use this fit document (from 'fogbayes fit --json'), or "
                                  "apply a loop document's calibration (from 'fogbayes loop "
                                  "--json') to this recording."),
    loop_json: Path = typer.Option(None, "--loop", help="Re-run and tell the closed loop "
                                   "recorded in this JSON (from 'fogbayes loop --json')."),
    bayes: bool = typer.Option(False, help="Posterior intervals (NumPyro) with --model."),
    pdf: Path = typer.Option(None, help="Also print the report to this PDF (headless Chromium)."),
    seed: int = typer.Option(0, help="Random seed of the samplers."),
    time_unit: str = TIME_UNIT_OPT,
    quiet: bool = QUIET_OPT,
):
    """Write a calibration report: recording, fitted model, residuals, compensation, noise.

    One self-contained HTML file (figures embedded): the recording, the fitted model with its coefficients and intervals, residuals against time and each covariate, bias stability before/after compensation, and the Allan deviation. Without --model, --fit or --loop it describes the recording and its noise only.

    Examples:
      fogbayes report chamber.csv --model thermal --out chamber_report.html
      fogbayes report chamber.csv --fit fit.json --pdf report.pdf
      fogbayes report chamber.csv --loop loop.json --out loop_report.html
    """
    from ..errors import about_file
    from ..workflow.report import build_report, print_pdf

    refuse_overwrite({"the recording": rec_path, "the --fit document": fit,
                      "the --loop document": loop_json}, {"--out": out, "--pdf": pdf})
    from ..data.documents import agreed_unit, read_calibration

    from ..data.axes_doc import per_axis

    fit_doc = read_calibration(fit) if fit else None  # fit, loop or axes document, validated
    # a multi-axis document: its axes share the recording, and so its unit
    unit_doc = per_axis(fit_doc)[0][1] if fit_doc else None
    output_unit = reading_options()["output_unit"]
    rec = load_recording(rec_path, time_unit=time_unit,
                         output_unit=agreed_unit(unit_doc, str(fit), rec_path, output_unit)
                         if fit_doc else output_unit)
    loop_res = None
    from ..data.atomic import all_or_none, pending

    with all_or_none():  # --out and --pdf appear both or neither
        with progress("building the report"), about_file(rec_path):
            if loop_json:
                from ..loop import run_loop

                doc = _read_json(loop_json, "loop")
                loop_res = run_loop(rec, doc.get("model", model or "bias-t"),
                                    max_steps=max(1, len(doc.get("steps", [])) or 1),
                                    seed=seed)
            path = build_report(rec, out, model=model, fit=fit_doc, loop=loop_res,
                                bayes=bayes, seed=seed, fit_source=str(fit) if fit else None)
        if pdf:
            _print(print_pdf, pending(path), pdf)  # from the HTML not yet renamed into place
    say(f"wrote {path}")
    if pdf:
        say(f"wrote {pdf}")


def _print(print_pdf, html: Path, pdf: Path) -> None:
    """``print_pdf`` with a failure of the browser (an exit status, a hang, a binary that
    will not start) as one line naming --pdf: no HTML or PDF is left (all or none)."""
    import subprocess

    from ..errors import FogbayesError

    try:
        print_pdf(html, pdf)
    except (subprocess.CalledProcessError, subprocess.TimeoutExpired, OSError) as exc:
        why = (f"exit status {exc.returncode}" if isinstance(exc, subprocess.CalledProcessError)
               else "no answer in 300 s" if isinstance(exc, subprocess.TimeoutExpired)
               else exc.strerror or str(exc))
        raise FogbayesError(f"headless Chromium could not print the report ({why})",
                            file=str(pdf), column="--pdf",
                            fix="drop --pdf and print the HTML from a browser") from None
