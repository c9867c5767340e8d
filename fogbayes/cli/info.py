"""``fogbayes info REC``: what is in a recording (sampling, gaps, channels, ranges)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import typer

from ._app import app
from ._common import REC_ARG, load_recording, write_json


@app.command()
def info(
    rec_path: Path = REC_ARG,
    column: str = typer.Option("output", help="Name of the gyro output column."),
    time_column: str = typer.Option("time", help="Name of the time column (s)."),
    output_unit: str = typer.Option(None, help="Output unit (deg/h, deg/s, rad/s, V, mV, Hz); default from the file, else deg/h."),
    json_out: str = typer.Option(None, "--json", help="Also write the summary as JSON ('-' for stdout)."),
):
    """Summarise a recording: samples, rate, gaps, temperature and output ranges.

    Example: fogbayes info chamber_run.csv --output-unit deg/s
    """
    rec = load_recording(rec_path, column=column, time_column=time_column, output_unit=output_unit)
    s = rec.sampling()
    summary = {
        "file": str(rec_path), "sensor_id": rec.meta.sensor_id, "n": rec.n,
        "duration_s": s.duration, "sample_rate_hz": s.sample_rate, "irregular": s.irregular,
        "gaps": [{"index": g.index, "start_s": g.start, "duration_s": g.duration} for g in s.gaps],
        "unit": rec.unit, "output_mean": float(np.mean(rec.output)), "output_std": float(np.std(rec.output)),
        "temperatures": {nm: {"min": float(rec.temperatures[:, j].min()), "max": float(rec.temperatures[:, j].max())}
                         for j, nm in enumerate(rec.temperature_names)},
        "input_rate": None if rec.input_rate is None else
        {"min": float(rec.input_rate.min()), "max": float(rec.input_rate.max())},
    }
    if json_out:
        write_json(summary, json_out)
    if json_out != "-":
        typer.echo(repr(rec))
        if s.gaps:
            typer.echo(f"{len(s.gaps)} gap(s) kept as they are (never interpolated); longest "
                       f"{max(g.duration for g in s.gaps):.3g} s at t = {max(s.gaps, key=lambda g: g.duration).start:.6g} s")
        if s.irregular:
            typer.echo("sampling is irregular (time steps vary by more than 1 % outside gaps)")
