"""``fogbayes compensate REC --params FIT --out OUT.csv``: apply a fitted model.

The output CSV has one row per input row: ``time``, the compensated ``output`` in the
input unit (``rate`` in deg/s for the composite model) and a boolean ``outlier`` column
(3-sigma flags; nothing is dropped).
"""

from __future__ import annotations

from pathlib import Path

import typer

from ._app import app
from ._common import (COLUMN_OPT, INPUT_RATE_OPT, QUIET_OPT, REC_ARG, TEMPERATURE_OPT,
                      TIME_COLUMN_OPT, load_recording, progress, refuse_overwrite, say,
                      write_json)
from ._common import TEMPERATURE_OFFSET_OPT, TEMPERATURE_SCALE_OPT, TIME_UNIT_OPT
from ._common import AXIS_OPT, INSTANCE_OPT, TOPIC_OPT


def read_fit(path: Path) -> dict:
    """The validated fit or loop document at ``path`` (:mod:`fogbayes.data.documents`)."""
    from ..data.documents import read_calibration

    return read_calibration(path)


def loop_summary(rec, doc: dict, applied, *, rec_path, params, out) -> dict:
    """The ``--json`` document of a loop calibration applied to ``rec``: rows, outliers,
    run events left out, covariates outside the calibrated range and, for the bias family,
    10 s RMS and bias stability before/after (:mod:`fogbayes.loop.metrics`)."""
    from ..loop.metrics import block_rms
    from ..stats.stability import stability_report

    cols = applied.columns
    out_doc = {"file": str(rec_path), "params": str(params), "out": str(out),
               "model": doc.get("model"), "schema": doc.get("schema"),
               "rows": int(len(cols["time"])), "outliers": int(cols["outlier"].sum()),
               "columns": list(cols), "terms_applied": [
                   t["effect"] + ":" + t["kind"] for t in doc["calibration"]["terms"]
                   if t["kind"] not in {s["kind"] for s in applied.skipped}],
               "run_events_left_out": applied.skipped, "outside_calibrated_range":
               applied.outside}
    if applied.bias_deg_h is not None:
        before = rec.rate("deg/h")
        after = before - applied.bias_deg_h
        t, flag = cols["time"], cols["outlier"]
        out_doc["unit"] = rec.unit
        out_doc["rms_10s_deg_h"] = {"before": block_rms(t, before, flag),
                                    "after": block_rms(t, after, flag),
                                    "after_about_mean": block_rms(
                                        t, after - after[~flag].mean(), flag)}
        out_doc["metrics"] = stability_report(before, after, t)
    return out_doc


def compensate_with_loop(doc: dict, recording, *, rec_path, params, out, json_out,
                         run_events: bool) -> None:
    """Apply the calibration of a loop document to ``recording`` and write the outputs."""
    from ..data import write_csv_mixed
    from ..errors import about_file
    from ..loop.calibration import apply_calibration

    with progress(f"compensating {recording.n} samples (loop calibration, {doc['model']})"), \
            about_file(rec_path):
        applied = apply_calibration(doc, recording, run_events=run_events)
        write_csv_mixed(out, applied.columns)
    cols = applied.columns
    say(f"wrote {out}: {len(cols['time'])} rows, {int(cols['outlier'].sum())} flagged as "
        "outliers")
    tell_loop_notes(applied.skipped, applied.outside)
    summ = loop_summary(recording, doc, applied, rec_path=rec_path, params=params, out=out)
    if "rms_10s_deg_h" in summ:
        r = summ["rms_10s_deg_h"]
        say(f"10 s RMS {r['before']:.4g} -> {r['after']:.4g} deg/h")
    if json_out:
        write_json(summ, json_out)


def stream_with_loop(doc: dict, source, *, rec_path, params, out, json_out, run_events: bool,
                     rows: int) -> None:
    """Apply a loop document's calibration chunk by chunk (:mod:`fogbayes.stream.loop_calibration`)."""
    from ..errors import about_file
    from ..stream.loop_calibration import compensate_loop_stream

    with progress(f"compensating {rec_path} in chunks of {rows} rows (loop calibration, "
                  f"{doc['model']})"), about_file(rec_path):
        res = compensate_loop_stream(source, doc, out, rows=rows, run_events=run_events)
    say(f"wrote {res.path}: {res.n} rows, {res.outliers} flagged as outliers")
    tell_loop_notes(res.skipped, res.outside)
    if res.rms_10s is not None:
        say(f"10 s RMS {res.rms_10s['before']:.4g} -> {res.rms_10s['after']:.4g} deg/h")
    if json_out:
        write_json({"file": str(rec_path), "params": str(params), "out": str(res.path),
                    "model": doc.get("model"), "schema": doc.get("schema"), "rows": res.n,
                    "outliers": res.outliers, "columns": list(res.columns),
                    "terms_applied": [t["effect"] + ":" + t["kind"]
                                      for t in doc["calibration"]["terms"]
                                      if t["kind"] not in {s["kind"] for s in res.skipped}],
                    "run_events_left_out": res.skipped,
                    "outside_calibrated_range": res.outside, "passes": res.passes,
                    **({} if res.rms_10s is None else {"rms_10s_deg_h": res.rms_10s,
                                                       "metrics": res.metrics})},
                   json_out)


def tell_loop_notes(skipped: list, outside: list) -> None:
    """Say which run events were left out and which covariates left the calibrated range."""
    for s in skipped:
        say(f"left out {s['effect']} ({s['kind']}): a run event of the calibration run; "
            "--run-events applies it")
    for o in outside:
        (lo, hi), (slo, shi) = o["calibrated"], o["seen"]
        say(f"warning: {o['covariate']} outside the calibrated range [{lo:.3g}, {hi:.3g}] on "
            f"{100 * o['share']:.1f} % of the samples (seen [{slo:.3g}, {shi:.3g}]): "
            "extrapolated")


def summary(rec, fit_doc: dict, cols: dict, *, rec_path, params, out) -> dict:
    """The ``--json`` document: what was compensated and, for bias models, the bias
    stability before/after (paper 004 eq. 13, :func:`fogbayes.stats.stability.stability_report`)."""
    from ..stats.stability import stability_report
    from ..data.units import convert_rate

    doc = {"file": str(rec_path), "params": str(params), "out": str(out),
           "model": fit_doc.get("model"), "rows": int(len(cols["time"])),
           "outliers": int(cols["outlier"].sum()) if "outlier" in cols else 0,
           "columns": list(cols)}
    if "output" in cols:  # bias models: output in the input unit; metrics in deg/h
        after = convert_rate(cols["output"], rec.unit, "deg/h", scale_factor=rec.scale_factor)
        doc["unit"] = rec.unit
        doc["metrics"] = stability_report(rec.rate("deg/h"), after, rec.time)
    return doc


@app.command()
def compensate(
    rec: Path = REC_ARG,
    params: Path = typer.Option(..., "--params", "--fit", "-p",
                                help="Fit document from 'fogbayes fit --json', or a loop "
                                "document from 'fogbayes loop --json'."),
    out: Path = typer.Option(..., "--out", "-o", help="Compensated CSV to write."),
    json_out: str = typer.Option(None, "--json", help="Also write a summary document (rows, "
                                 "outliers, bias stability before/after) ('-' = stdout)."),
    column: str = COLUMN_OPT,
    time_column: str = TIME_COLUMN_OPT,
    time_unit: str = TIME_UNIT_OPT,
    topic: str = TOPIC_OPT,
    instance: int = INSTANCE_OPT,
    axis: str = AXIS_OPT,
    output_unit: str = typer.Option(None, "--output-unit", show_default=False,
                                    rich_help_panel="Reading the recording",
                                    help="Output unit; says which is right when the file's '# unit:' "
                                    "line and the fit's unit differ (default: those, which "
                                    "must agree)."),
    scale_factor: float = typer.Option(None, "--scale-factor", show_default=False,
                                       rich_help_panel="Reading the recording",
                                       help="Raw units per deg/s (default: the fit's)."),
    temperature: list[str] = TEMPERATURE_OPT,
    input_rate: str = INPUT_RATE_OPT,
    temperature_scale: float = TEMPERATURE_SCALE_OPT,
    temperature_offset: float = TEMPERATURE_OFFSET_OPT,
    stream: bool = typer.Option(False, "--stream",
                                help="Bounded memory, chunk by chunk: REC is .npz, .parquet, "
                                "a .npy or a folder of <column>.npy; OUT is .npz, .parquet "
                                "or a folder (same numbers as the in-memory path)."),
    chunk_rows: int = typer.Option(1 << 20, "--chunk-rows", min=1024,
                                   help="Rows read at a time with --stream."),
    run_events: bool = typer.Option(False, "--run-events",
                                    help="With a loop document: also apply the calibration "
                                    "run's own events (a step, a linear drift, a periodic "
                                    "term); by default only the sensor's properties are."),
    quiet: bool = QUIET_OPT,
):
    """Compensate a recording with a fitted model; every input row is written.

    The CSV has one row per input row: time, the compensated output in the input unit (for the composite model: the estimated input rate in deg/s) and a boolean outlier column (3-sigma flags; nothing is dropped).

    Examples:
      fogbayes compensate run.csv --params fit.json --out compensated.csv
      fogbayes compensate run.csv -p fit.json -o comp.csv --json summary.json
      fogbayes -q compensate run.csv -p fit.json -o comp.csv --json -
      fogbayes compensate big.parquet -p fit.json -o comp.parquet --stream
      fogbayes compensate next_run.csv -p loop.json -o comp.csv --json summary.json
    """
    from ..data import write_csv_mixed
    from ..data.atomic import all_or_none
    from ..errors import FogbayesError, about_file
    from ..workflow import workflow_for

    refuse_overwrite({"the recording": rec, "the --params document": params},
                     {"--out": out, "--json": json_out},
                     folders=("--out",) if stream else ())  # --stream may write a folder
    fit_doc = read_fit(params)
    from ..data.axes_doc import is_axes_document
    from ..data.documents import agreed_unit, check_channels
    from ..data.doc_rules import is_loop_document

    if is_axes_document(fit_doc):
        raise FogbayesError(f"a multi-axis {fit_doc['model']!r} document: compensation takes "
                            "the document of one axis", file=str(params), column="--params",
                            fix="fit the axis to compensate on its own (--axis x) and pass "
                                "that document")

    def stream_source(unit, names=None):
        """The record opened for chunked reading (what --stream can read)."""
        from ..data.logs import is_log
        from ..stream import open_source

        if is_log(rec) or topic is not None or instance is not None or axis is not None:
            raise FogbayesError("--stream reads .npz, .parquet and .npy files, not gyro logs",
                                column="--stream",
                                fix="drop --stream (a log is read into memory), or drop "
                                    "--topic/--instance/--axis")
        given = fit_doc.get("input") or {}
        return open_source(rec, time=time_column or "time", output=column or "output",
                           temperature=list(temperature or []) or names,
                           input_rate=input_rate or "input_rate", unit=unit,
                           scale_factor=scale_factor if scale_factor is not None
                           else given.get("scale_factor"), time_unit=time_unit,
                           temperature_scale=temperature_scale,
                           temperature_offset=temperature_offset)

    if is_loop_document(fit_doc):
        if fit_doc["model"] == "allan":
            raise FogbayesError(
                "this loop document describes noise only: there is nothing to compensate",
                file=str(params), column="--params",
                fix="compensate with a bias-t, thermal or composite loop document")
        if stream:
            src = stream_source(agreed_unit(fit_doc, str(params), rec, output_unit))
            stream_with_loop(fit_doc, src, rec_path=rec, params=params, out=out,
                             json_out=json_out, run_events=run_events, rows=chunk_rows)
            return
        given = fit_doc.get("input") or {}
        recording = load_recording(
            rec, column=column, time_column=time_column,
            output_unit=agreed_unit(fit_doc, str(params), rec, output_unit),
            scale_factor=scale_factor if scale_factor is not None else given.get("scale_factor"),
            temperature=temperature, input_rate=input_rate, time_unit=time_unit,
            temperature_scale=temperature_scale, temperature_offset=temperature_offset,
            topic=topic, instance=instance, axis=axis)
        with all_or_none():  # --out and --json appear both or neither
            compensate_with_loop(fit_doc, recording, rec_path=rec, params=params, out=out,
                                 json_out=json_out, run_events=run_events)
        return
    if run_events:
        raise FogbayesError("--run-events applies to loop documents only", column="--run-events",
                            fix="drop --run-events with a fit document")
    wf = workflow_for(str(fit_doc["model"]))
    if getattr(wf, "compensate_recording", None) is None or fit_doc["model"] == "allan":
        raise FogbayesError(f"model '{fit_doc['model']}' describes noise: there is nothing to "
                            "compensate", file=str(params), field="model",
                            fix="compensate with a bias-t, thermal or composite fit")
    given = fit_doc.get("input") or {}
    unit = agreed_unit(fit_doc, str(params), rec, output_unit)  # file, document, option agree
    if stream:
        from ..stream import compensate_stream

        src = stream_source(unit)
        with progress(f"compensating {rec} in chunks of {chunk_rows} rows ({fit_doc['model']})"), \
                about_file(rec):
            res = compensate_stream(src, fit_doc, out, rows=chunk_rows,
                                    metrics=json_out is not None)
        say(f"wrote {res.path}: {res.n} rows, {res.outliers} flagged as outliers")
        if json_out:
            write_json({"file": str(rec), "params": str(params), "out": str(res.path),
                        "model": fit_doc.get("model"), "rows": res.n, "outliers": res.outliers,
                        "columns": list(res.columns), "passes": res.passes,
                        **({} if res.metrics is None else {"unit": src.unit,
                                                           "metrics": res.metrics})},
                       json_out)
        return
    recording = load_recording(rec, column=column, time_column=time_column,
                               output_unit=unit,
                               scale_factor=scale_factor if scale_factor is not None
                               else given.get("scale_factor"),
                               temperature=temperature, input_rate=input_rate,
                               time_unit=time_unit, temperature_scale=temperature_scale,
                               temperature_offset=temperature_offset,
                               topic=topic, instance=instance, axis=axis)
    check_channels(fit_doc, str(params), recording)
    with all_or_none():  # --out and --json appear both or neither
        with progress(f"compensating {recording.n} samples ({fit_doc['model']})"), \
                about_file(rec):
            cols = wf.compensate_recording(recording, fit_doc)
            write_csv_mixed(out, cols)
        if json_out:
            write_json(summary(recording, fit_doc, cols, rec_path=rec, params=params, out=out),
                       json_out, tell=False)
    n_out = int(cols["outlier"].sum()) if "outlier" in cols else 0
    say(f"wrote {out}: {len(cols['time'])} rows, {n_out} flagged as outliers")
    if json_out and json_out != "-":
        say(f"wrote {json_out}")
