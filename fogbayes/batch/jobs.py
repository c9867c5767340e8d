"""One recording of a fleet -> its output files and one summary row.

``run_one(path, model=, task=, out_dir=, options=)`` runs ``fit`` (``<stem>.fit.json``),
``compensate`` (also ``<stem>.compensated.csv``; with ``params`` one calibration for all),
``loop`` (:func:`fogbayes.loop.run_loop`, ``<stem>.loop.json``) or ``report``
(:func:`fogbayes.workflow.report.build_report`, ``<stem>.html``) with the single-recording
calls. Any exception becomes ``{"file", "status": "error", "error"}``; picklable for Dask.
"""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Any, NamedTuple

import fogbayes  # noqa: F401  (float64 on in every process that runs a job)

from ..errors import FogbayesError


class JobOptions(NamedTuple):
    """What every recording of a fleet is run with (picklable, JSON-able).

    Attributes:
        orders: model orders as ``fogbayes fit --orders`` / ``fogbayes loop --orders`` take.
        seed: seed of samplers and bootstrap draws.
        fit_options: workflow options (``fogbayes fit --option KEY=VALUE``).
        load: :func:`fogbayes.data.load` keywords (``time``, ``output``, ``unit``,
            ``scale_factor``, ``temperature``).
        bayes: also compute the posterior in ``fit``/``compensate``/``report``.
        max_steps, alpha: of the closed loop (``task="loop"``).
        params: a validated fit or loop document to apply instead of fitting
            (``task="compensate"``; :func:`fogbayes.data.documents.read_calibration`).
    """

    orders: str | None = None
    seed: int = 0
    fit_options: dict | None = None
    load: dict | None = None
    bayes: bool = False
    max_steps: int = 5
    alpha: float = 0.01
    params: dict | None = None


def as_options(options: JobOptions | dict | None) -> JobOptions:
    if options is None:
        return JobOptions()
    if isinstance(options, JobOptions):
        return options
    return JobOptions(**options)


#: The files each task writes per recording, ``<stem><suffix>`` in OUT (see the module doc).
OUTPUT_SUFFIXES = {"fit": (".fit.json",), "compensate": (".fit.json", ".compensated.csv"),
                   "loop": (".loop.json", ".compensated.csv"), "report": (".html",)}


def output_names(stem: str) -> list[str]:
    """Every per-recording output name any task writes for the recording ``stem``."""
    return sorted({stem + sfx for sfxs in OUTPUT_SUFFIXES.values() for sfx in sfxs})


def write_json(obj: Any, path: Path) -> Path:
    """The JSON text the command line writes (``fogbayes fit --json``), quietly, atomically."""
    from ..support.jsonable import to_jsonable
    from ..data.atomic import write_text

    return write_text(Path(path), json.dumps(to_jsonable(obj), indent=2) + "\n")


def error_message(exc: BaseException) -> str:
    """A FogbayesError's own message (it names file, column, row and fix), else type: text."""
    return str(exc) if isinstance(exc, FogbayesError) else f"{type(exc).__name__}: {exc}"


def error_row(path: str | Path, exc: BaseException) -> dict:
    return {"file": str(path), "status": "error", "error": error_message(exc)}


def fit_numbers(doc: dict) -> dict:
    """Key numbers of a fit document for the summary (those the model's document has)."""
    out: dict[str, Any] = {"converged": bool(doc.get("converged", False))}
    if isinstance(doc.get("outliers"), dict) and "count" in doc["outliers"]:
        out["n_outliers"] = int(doc["outliers"]["count"])
    rows = ((doc.get("metrics") or {}).get("full") or {}).get("stability") or []
    if rows:  # the shortest window: the figure paper 004 reports (1 s)
        out.update(bs_window_s=rows[0]["window_s"], bs_before=rows[0]["before"],
                   bs_after=rows[0]["after"])
    if "residual_rate_rms" in doc:  # composite: rms of the recovered input rate, deg/s
        out["residual_rate_rms"] = doc["residual_rate_rms"]
    return out


def fit_outputs(rec, path: Path, doc: dict, *, task: str, out_dir: Path) -> dict:
    """Write a fit document (and, for ``compensate``, the compensated CSV); the row's body."""
    from ..data.io import write_csv_mixed
    from ..workflow import workflow_for

    stem = Path(path).stem
    outputs = {"fit": write_json(doc, out_dir / f"{stem}.fit.json").name}
    row = fit_numbers(doc)
    if task == "compensate":
        cols = workflow_for(doc["model"]).compensate_recording(rec, doc)
        outputs["compensated"] = write_csv_mixed(out_dir / f"{stem}.compensated.csv", cols).name
        if "outlier" in cols:
            row["n_flagged_after"] = int(cols["outlier"].sum())
    return {"outputs": outputs, **row}


def _apply(rec, path, out_dir, doc: dict) -> dict:
    """Apply one calibration ``doc`` to ``rec``: ``<stem>.compensated.csv`` and the row."""
    from ..data.doc_rules import is_loop_document
    from ..data.documents import check_channels
    from ..data.io import write_csv_mixed
    from ..loop.metrics import block_rms
    from ..stats.stability import stability_report
    from ..data.units import convert_rate

    before = rec.rate("deg/h")
    row: dict[str, Any] = {}
    after = None  # composite: the output is the input rate, no before/after of a bias
    if is_loop_document(doc):
        from ..loop.calibration import apply_calibration

        applied = apply_calibration(doc, rec)
        cols = applied.columns
        if applied.bias_deg_h is not None:
            after = before - applied.bias_deg_h
        row["run_events_left_out"] = [s["effect"] for s in applied.skipped]
        row["outside_calibrated_range"] = [o["covariate"] for o in applied.outside]
    else:
        from ..workflow import workflow_for

        check_channels(doc, "--params", rec)
        cols = workflow_for(doc["model"]).compensate_recording(rec, doc)
        if "output" in cols:
            after = convert_rate(cols["output"], rec.unit, "deg/h",
                                 scale_factor=rec.scale_factor)
    flag = cols["outlier"]
    row["n_flagged_after"] = int(flag.sum())
    if after is not None:
        rows = stability_report(before, after, rec.time)["stability"]
        row.update(rms_before=block_rms(rec.time, before, flag),
                   rms_after=block_rms(rec.time, after, flag))
        if rows:  # the shortest window: the figure paper 004 reports (1 s)
            row.update(bs_window_s=rows[0]["window_s"], bs_before=rows[0]["before"],
                       bs_after=rows[0]["after"])
    name = write_csv_mixed(Path(out_dir) / f"{Path(path).stem}.compensated.csv", cols).name
    return {"outputs": {"compensated": name}, **row}


def _fit(rec, path, model, out_dir, opts: JobOptions, task: str) -> dict:
    from ..workflow import workflow_for

    if task == "compensate" and opts.params is not None:
        return _apply(rec, path, out_dir, opts.params)
    doc = workflow_for(model).fit_recording(rec, model=model, orders=opts.orders,
                                            bayes=opts.bayes, seed=opts.seed,
                                            **(opts.fit_options or {}))
    return fit_outputs(rec, path, doc, task=task, out_dir=out_dir)


def _loop(rec, path, model, out_dir, opts: JobOptions, task: str) -> dict:
    from ..data.io import write_csv_mixed
    from ..loop import run_loop

    res = run_loop(rec, model, orders=opts.orders, max_steps=opts.max_steps, alpha=opts.alpha,
                   seed=opts.seed)
    stem = Path(path).stem
    outputs = {"loop": write_json(res.to_json(), out_dir / f"{stem}.loop.json").name,
               "compensated": write_csv_mixed(out_dir / f"{stem}.compensated.csv",
                                              res.compensated).name}
    return {"outputs": outputs, "effects": list(res.effects), "stop": res.stop.reason,
            "rms_before": res.initial.rms, "rms_after": res.final.rms,
            "bias_stability_before": res.initial.bias_stability,
            "bias_stability_after": res.final.bias_stability}


def _report(rec, path, model, out_dir, opts: JobOptions, task: str) -> dict:
    from ..workflow.report import build_report

    out = out_dir / f"{Path(path).stem}.html"
    build_report(rec, out, model=model, bayes=opts.bayes, seed=opts.seed,
                 title=f"Calibration report: {Path(path).name}")
    return {"outputs": {"report": out.name}}


_TASKS = {"fit": _fit, "compensate": _fit, "loop": _loop, "report": _report}


def load_one(path: str | Path, options: JobOptions | dict | None = None):
    """The recording at ``path`` with the fleet's column/unit overrides; with a calibration
    to apply, in the unit its document, the file and ``--output-unit`` agree on."""
    from ..data import load

    opts = as_options(options)
    kw = dict(opts.load or {})
    if opts.params is not None:
        from ..data.documents import agreed_unit

        kw["unit"] = agreed_unit(opts.params, "--params", path, kw.get("unit"))
        if kw.get("scale_factor") is None:
            kw["scale_factor"] = (opts.params.get("input") or {}).get("scale_factor")
    return load(path, **kw)


def run_one(path: str | Path, *, model: str, task: str = "fit", out_dir: str | Path,
            options: JobOptions | dict | None = None) -> dict:
    """Run ``task`` on the recording at ``path``; write its outputs into ``out_dir``.

    Returns the summary row (see the module doc); never raises for a bad recording.
    """
    t0 = time.perf_counter()
    try:
        if task not in _TASKS:
            raise FogbayesError(f"unknown task '{task}'", column="task",
                                fix=f"use one of {', '.join(_TASKS)}")
        opts = as_options(options)
        rec = load_one(path, opts)
        row = {"file": str(path), "status": "ok",
               **_TASKS[task](rec, Path(path), model, Path(out_dir), opts, task)}
    except Exception as exc:  # noqa: BLE001  one bad recording must not stop the fleet
        row = error_row(path, exc)
    row["seconds"] = time.perf_counter() - t0
    return row
