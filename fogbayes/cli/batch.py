"""``fogbayes batch DIR --model NAME --out DIR``: one task over a fleet of recordings.

Wires :func:`fogbayes.batch.run_batch` (``--engine local|dask``, ``--workers``, ``--address``,
``--vectorize``). Exit 0 all succeeded, 1 any failed (``OUT/summary.json`` either way), 2 the run
could not start.
"""

from __future__ import annotations

from pathlib import Path

import typer

from ._app import app
from ._common import (QUIET_OPT, TIME_UNIT_OPT, check_inputs, load_keywords, progress,
                      reading_options, refuse_overwrite, say, write_json)

_EPILOG = """Examples:

  fogbayes batch runs/ --model bias-t --out fits/

  fogbayes batch runs/ --model thermal --task compensate --engine dask --workers 4 --out comp/

  fogbayes batch runs/ --model bias-t --engine dask --address tcp://10.0.0.5:8786 --out fits/

  fogbayes batch runs/ --model thermal --orders 2 --vectorize --out fits/ --json -

  fogbayes batch next_runs/ -m bias-t --task compensate --params loop.json --out comp/
"""


@app.command(epilog=_EPILOG)
def batch(
    folder: Path = typer.Argument(..., help="Folder of recordings (.csv, .parquet, .npz).",
                                  show_default=False),
    model: str = typer.Option(..., "--model", "-m",
                              help="bias-t | thermal | composite | allan | arma."),
    out: Path = typer.Option(..., "--out", "-o", help="Folder for the outputs and summary.json."),
    task: str = typer.Option("fit", "--task", help="fit | compensate | loop | report."),
    engine: str = typer.Option("local", "--engine", help="local (this process) | dask."),
    address: str = typer.Option(None, "--address",
                                help="Dask scheduler, e.g. tcp://host:8786 (default: start a "
                                     "local cluster)."),
    workers: int = typer.Option(2, "--workers", help="Worker processes of the local Dask cluster."),
    pattern: str = typer.Option("*.csv", "--pattern",
                                help="File pattern(s) in DIR, comma-separated, e.g. '*.csv,*.npz'."),
    vectorize: bool = typer.Option(False, "--vectorize",
                                   help="bias-t/thermal, same length and sampling: one batched "
                                        "least-squares solve for all recordings."),
    orders: str = typer.Option(None, "--orders", "--order", help="Model order(s), as in 'fogbayes fit'."),
    option: list[str] = typer.Option(None, "--option", "-O",
                                     help="Model option KEY=VALUE (repeatable), as in 'fogbayes fit'."),
    bayes: bool = typer.Option(False, "--bayes", help="Also compute the posterior (fit/compensate/report)."),
    max_steps: int = typer.Option(5, "--max-steps", min=0, help="Loop: add at most this many effects."),
    alpha: float = typer.Option(0.01, help="Loop: family-wise false-effect level of each step."),
    seed: int = typer.Option(0, help="Seed of samplers and bootstrap draws."),
    params: Path = typer.Option(None, "--params", "-p",
                                help="Task compensate: apply this fit or loop document to "
                                     "every recording instead of fitting each."),
    json_out: str = typer.Option(None, "--json", help="Also write the summary here ('-' = stdout)."),
    time_unit: str = TIME_UNIT_OPT,
    quiet: bool = QUIET_OPT,
):
    """Fit, compensate, loop or report every recording of a folder, in-process or on Dask.

    Every output is written atomically; summary.json is removed when the work starts and written last, so it exists only for a finished run. On a re-run into the same folder, a recording's outputs from the earlier run that this run did not write (e.g. the old .fit.json of a recording that now fails) are removed; files of other recordings are left alone.
    """
    from ..batch import JobOptions, find_recordings, run_batch
    from ..batch.jobs import OUTPUT_SUFFIXES
    from .fit import parse_option_pairs

    # the keywords of fogbayes.data.load, as load_recording passes them (every file alike)
    given = {**reading_options(), "time_unit": time_unit}
    load = load_keywords(given)
    from ..data.checks import finite, time_divisor

    if time_unit is not None:
        time_divisor(time_unit)  # bad reading options: exit 2 now, not one failure per file
    finite(given["temperature_scale"], "--temperature-scale", nonzero=True)
    finite(given["temperature_offset"], "--temperature-offset")
    if given["scale_factor"] is not None:
        finite(given["scale_factor"], "--scale-factor", positive=True)
    opts = JobOptions(orders=orders, seed=seed, fit_options=parse_option_pairs(option),
                      load=load, bayes=bayes, max_steps=max_steps, alpha=alpha,
                      params=_calibration(params, task, model, vectorize))
    where = f"dask ({address or f'local cluster, {workers} workers'})" if engine == "dask" else engine
    check_inputs({"the recordings folder": folder})  # unreadable: say so, not "no match"
    files = find_recordings(folder, pattern)  # bad folder/pattern: exit 2 right away
    n_files = len(files)
    refuse_overwrite({"a recording": files},
                     {"--out": Path(out) / "summary.json", "--json": json_out,
                      "a per-recording output": [Path(out) / f"{f.stem}{sfx}" for f in files
                                                 for sfx in OUTPUT_SUFFIXES.get(task, ())]})
    with progress(f"{task} {model}: {n_files} recordings [{where}]", total=n_files) as advance:
        def done(row: dict) -> None:
            advance(1)
            if row["status"] != "ok":
                say(f"failed: {row['error']}")

        summary = run_batch(folder, model=model, out=out, task=task, engine=engine,
                            address=address, workers=workers, pattern=pattern,
                            vectorize=vectorize, options=opts, on_done=done)
    if json_out:
        write_json(summary, json_out)
    say(f"{task} {model}: {summary['n_ok']} of {summary['n_files']} recordings ok in "
        f"{summary['seconds']:.1f} s on {where}; wrote {Path(out) / 'summary.json'}")
    if summary["n_error"]:
        raise typer.Exit(1)


def _calibration(params: Path | None, task: str, model: str, vectorize: bool) -> dict | None:
    """The validated document ``--params`` names (one line and exit 2 for what cannot be)."""
    if params is None:
        return None
    from ..data.axes_doc import is_axes_document
    from ..data.documents import read_calibration
    from ..errors import FogbayesError

    if task != "compensate" or vectorize:
        raise FogbayesError("--params applies one calibration with --task compensate",
                            column="--params", fix="use --task compensate (without "
                            "--vectorize), or drop --params to fit every recording")
    doc = read_calibration(params)
    if is_axes_document(doc) or doc.get("model") != model or model in ("allan", "arma"):
        what = "a multi-axis document" if is_axes_document(doc) else \
            f"a '{doc.get('model')}' document"
        raise FogbayesError(f"{what} cannot compensate model '{model}' recordings",
                            file=str(params), column="--params",
                            fix="pass the document of one axis of a bias-t, thermal or "
                                "composite model, and the same --model")
    return doc
