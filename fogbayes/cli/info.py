"""``fogbayes info REC``: what is in a recording (sampling, gaps, channels, ranges)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import typer

from ._app import app
from ._common import (QUIET_OPT, REC_ARG, TIME_UNIT_OPT, load_recording, refuse_overwrite,
                      time_notes, write_json)


def summary_document(rec, rec_path, time_unit: str | None = None) -> dict:
    """The ``--json`` document: size, sampling, gaps, unit, output and channel ranges; how
    the time column was read (``time_read``, when its name chose it) and ``hints`` (a time
    column stepping like a ms or us counter read in seconds: :func:`time_notes`)."""
    s = rec.sampling()
    read_as, hint = time_notes(rec, rec_path, time_unit)
    return {
        "file": str(rec_path), "sensor_id": rec.meta.sensor_id, "n": rec.n,
        "duration_s": s.duration, "sample_rate_hz": s.sample_rate, "irregular": s.irregular,
        "gaps": [{"index": g.index, "start_s": g.start, "duration_s": g.duration} for g in s.gaps],
        "unit": rec.unit, "scale_factor": rec.scale_factor,
        "output_mean": float(np.mean(rec.output)), "output_std": float(np.std(rec.output)),
        "temperatures": {nm: {"min": float(rec.temperatures[:, j].min()),
                              "max": float(rec.temperatures[:, j].max())}
                         for j, nm in enumerate(rec.temperature_names)},
        "input_rate": None if rec.input_rate is None else
        {"min": float(rec.input_rate.min()), "max": float(rec.input_rate.max())},
        **_log_part(rec.meta.extra),
        **({"time_read": read_as} if read_as else {}), "hints": [hint] if hint else [],
    }


def _log_part(extra: dict) -> dict:
    """For a gyro log: what the reader recorded (format, topic, instance, axis, temperature
    alignment, dropouts, firmware parameters) and the warnings about its rates."""
    if "log_format" not in extra:
        return {}
    from ..data.logs.firmware import rate_warnings

    keep = {k: v for k, v in extra.items() if isinstance(v, (str, int, float, bool))}
    return {"log": keep, "warnings": rate_warnings(extra)}


def text_summary(doc: dict) -> str:
    """The printed summary: what a calibration engineer checks before fitting."""
    dur = doc["duration_s"]
    span = f"{dur / 3600:.3g} h" if dur >= 3600 else f"{dur:.4g} s"
    gaps = f"{len(doc['gaps'])} gap(s)" if doc["gaps"] else "no gaps"
    lines = [f"{doc['file']}: sensor {doc['sensor_id']!r}, {doc['n']} samples, {span} at "
             f"{doc['sample_rate_hz']:.4g} Hz, {gaps}",
             f"  output ({doc['unit']}): mean {doc['output_mean']:.6g}, "
             f"std {doc['output_std']:.4g}"
             + (f", scale factor {doc['scale_factor']:.6g} per deg/s" if doc["scale_factor"] else "")]
    if doc["temperatures"]:
        for name, r in doc["temperatures"].items():
            lines.append(f"  {name}: {r['min']:.4g} ... {r['max']:.4g} degC")
    else:
        lines.append("  no temperature channel (thermal models need one)")
    if doc.get("time_read"):
        lines.append(f"  time column {doc['time_read']}")
    if doc["input_rate"] is not None:
        lines.append(f"  input_rate: {doc['input_rate']['min']:.6g} ... "
                     f"{doc['input_rate']['max']:.6g} deg/s")
    log = doc.get("log")
    if log:
        lines.append(f"  log: {log.get('log_format')}, {log.get('log_topic')} instance "
                     f"{log.get('log_instance')}, axis {log.get('axis', 'x')}; time "
                     f"{log.get('time_source')}")
    lines += [f"  warning: {w}" for w in doc.get("warnings") or []]
    lines += [f"  hint: {h}" for h in doc.get("hints") or []]
    return "\n".join(lines)


@app.command()
def info(
    rec_path: Path = REC_ARG,
    json_out: str = typer.Option(None, "--json", help="Also write the summary as a JSON "
                                 "document ('-' = stdout, instead of the text summary)."),
    time_unit: str = TIME_UNIT_OPT,
    quiet: bool = QUIET_OPT,
):
    """Summarise a recording: samples, rate, gaps, temperature and output ranges.

    Reading a file with 'info' is the quickest check of the data contract: a bad file gives one line naming the file, column and row, and exit code 2.

    Examples:
      fogbayes info chamber_run.csv
      fogbayes info gyro.csv --output-unit deg/s --time-column t_s
      fogbayes info lab.csv --delimiter ';' --decimal ','   # usually sniffed
      fogbayes info run.csv --json - > info.json
      fogbayes info flight.ulg --instance 1 --axis z
    """
    refuse_overwrite({"the recording": rec_path}, {"--json": json_out})
    rec = load_recording(rec_path, time_unit=time_unit, tell=False)
    s = rec.sampling()
    doc = summary_document(rec, rec_path, time_unit)
    if json_out:
        write_json(doc, json_out)
    if json_out != "-":
        typer.echo(text_summary(doc))
        if s.gaps:
            longest = max(s.gaps, key=lambda g: g.duration)
            typer.echo(f"{len(s.gaps)} gap(s) kept as they are (never interpolated); longest "
                       f"{longest.duration:.3g} s at t = {longest.start:.6g} s")
        if s.irregular:
            typer.echo("sampling is irregular (time steps vary by more than 1 % outside gaps)")
