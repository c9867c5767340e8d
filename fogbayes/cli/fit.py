"""``fogbayes fit REC --model NAME --json FIT``: fit a named model to a recording.

Dispatches on the model name to its workflow (``bias-t``/``thermal``, ``composite``,
``allan``; imported lazily by :func:`fogbayes.workflow.workflow_for`). Exit code 1 when the
fit did not converge and ``--strict`` is given; 2 for bad input.
"""

from __future__ import annotations

import json
from pathlib import Path

import typer

from ._app import app
from ._common import (COLUMN_OPT, INPUT_RATE_OPT, OUTPUT_UNIT_OPT, QUIET_OPT, REC_ARG,
                      SCALE_FACTOR_OPT, TEMPERATURE_OPT, TIME_COLUMN_OPT, load_recording,
                      progress, say, write_json)


def parse_option_pairs(items: list[str] | None) -> dict:
    """``KEY=VALUE`` pairs (VALUE as JSON when it parses, else as text) -> dict."""
    from ..errors import FogbayesError

    out = {}
    for item in items or []:
        key, sep, value = item.partition("=")
        if not sep or not key.strip():
            raise FogbayesError(f"option '{item}' is not KEY=VALUE", column="--option",
                                fix="write e.g. --option rate_window_s=30")
        try:
            out[key.strip().replace("-", "_")] = json.loads(value)
        except json.JSONDecodeError:
            out[key.strip().replace("-", "_")] = value
    return out


def summary_line(doc: dict) -> str:
    """One line for people: model, convergence and the full-temperature 1 s stability."""
    rows = doc.get("metrics", {}).get("full", {}).get("stability", [])
    first = rows[0] if rows else None
    bs = (f"; Bs({first['window_s']:g} s) {first['before']:.4g} -> {first['after']:.4g} deg/h "
          f"({first['improvement_pct']:.2f} % better)") if first else ""
    return f"{doc.get('model')}: converged={doc.get('converged')}{bs}"


@app.command()
def fit(
    rec: Path = REC_ARG,
    model: str = typer.Option(..., "--model", "-m",
                              help="bias-t | thermal | composite | allan | arma."),
    json_out: str = typer.Option(..., "--json", help="Fit document to write ('-' = stdout)."),
    orders: str = typer.Option(None, "--orders", "--order",
                               help="Order(s): bias-t '3' or '1-4'; thermal '2,2' or '1-3,1-2'; "
                                    "'auto' selects by the RMS criterion."),
    bayes: bool = typer.Option(False, "--bayes", help="Also compute the posterior (NUTS)."),
    seed: int = typer.Option(0, help="Seed of the posterior sampler."),
    processing: str = typer.Option(None, help="thermal models: 'default' or 'paper' (paper 004 exactly)."),
    noise: str = typer.Option(None, help="Posterior noise model: ar | white | arma."),
    option: list[str] = typer.Option(None, "--option", "-O",
                                     help="Model option KEY=VALUE (repeatable), e.g. rate_window_s=30."),
    strict: bool = typer.Option(False, help="Exit with code 1 when the fit did not converge."),
    column: str = COLUMN_OPT,
    time_column: str = TIME_COLUMN_OPT,
    output_unit: str = OUTPUT_UNIT_OPT,
    scale_factor: float = SCALE_FACTOR_OPT,
    temperature: list[str] = TEMPERATURE_OPT,
    input_rate: str = INPUT_RATE_OPT,
    quiet: bool = QUIET_OPT,
):
    """Fit a model to a recording and write the fit document as JSON.

    The document holds the coefficients in the scaled basis (what 'fogbayes compensate' uses) and in the papers' raw form with standard errors, the processing, outlier counts, bias stability before/after (thermal models) and, with --bayes, posterior intervals and convergence.

    Examples:
      fogbayes fit run.csv --model thermal --json fit.json
      fogbayes fit run.csv -m bias-t --orders auto --json fit.json
      fogbayes fit run.csv -m thermal --orders 2,2 --bayes --json fit.json
      fogbayes fit chamber.csv -m thermal --processing paper --json fit.json
      fogbayes -q fit table.csv -m composite --json - > fit.json
    """
    from ..workflow import workflow_for

    wf = workflow_for(model)
    options = parse_option_pairs(option)
    for key, value in (("processing", processing), ("noise", noise)):
        if value is not None:
            options[key] = value
    recording = load_recording(rec, column=column, time_column=time_column,
                               output_unit=output_unit, scale_factor=scale_factor,
                               temperature=temperature, input_rate=input_rate)
    with progress(f"fitting {model} to {recording.n} samples" + (" (posterior)" if bayes else "")):
        doc = wf.fit_recording(recording, model=model, orders=orders, bayes=bayes, seed=seed,
                               **options)
    write_json(doc, json_out)
    say(summary_line(doc))
    if strict and not doc.get("converged", False):
        say("the fit did not converge (--strict)")
        raise typer.Exit(1)
