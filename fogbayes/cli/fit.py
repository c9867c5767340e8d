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
from ._common import (QUIET_OPT, REC_ARG, TIME_UNIT_OPT, channels, fit_channels,
                      reading_options, refuse_overwrite, say, write_json)


#: The type of each known ``-O KEY=VALUE`` model option (the workflows' keywords): checked
#: here so that ``-O n_sigma=abc`` is one line naming the option, not a traceback.
_OPTION_TYPES = {
    # thermal processing (fogbayes.thermal.data.Processing) and model structure
    "processing": "text", "average_s": "positive", "temperature_average_s": "positive",
    "rate_method": "text", "rate_window_s": "positive", "outliers": "text",
    "n_sigma": "positive", "rate_gap_factor": "positive or null", "cross": "bool",
    "extra": "texts", "extra_order": "count", "temperature": "text or null",
    "order_criterion": "text", "windows": "positives",
    # posterior (thermal, allan, composite)
    "noise": "text", "ar_order": "integer", "ma_order": "integer", "num_warmup": "count",
    "num_samples": "count", "num_chains": "count", "level": "fraction",
    "bayes_average_s": "positive",
    # allan
    "taus": "text", "per_decade": "count", "select": "bool",
    # composite
    "method": "text", "operating_time": "text", "T_nominal": "number", "compensation": "text",
    "rate_tolerance": "non-negative", "temperature_tolerance": "non-negative",
    "rate_threshold": "non-negative", "min_duration": "non-negative", "trim_s": "non-negative",
    "stable_s": "non-negative", "smooth_s": "non-negative",
    # arma (fogbayes.arma.workflow.analyse_recording)
    "decimate": "count", "detrend_order": "integer", "candidates": "text", "criterion": "text",
    "lags": "count", "nlags": "count",
}
#: The only options the ARMA workflow takes (it has no check of its own for unknown ones).
_ARMA_OPTIONS = ("decimate", "detrend_order", "candidates", "criterion", "lags", "nlags")


def _typed(key: str, value, kind: str) -> bool:
    """Whether ``value`` (parsed JSON) is of the option type ``kind``."""
    import math

    def number(v) -> bool:
        return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)

    if kind.endswith(" or null") and value is None:
        return True
    kind = kind.removesuffix(" or null")
    if kind == "text":
        return isinstance(value, str)
    if kind == "texts":
        return isinstance(value, str) or (isinstance(value, list)
                                          and all(isinstance(v, str) for v in value))
    if kind == "bool":
        return isinstance(value, bool)
    if kind in ("integer", "count"):
        return number(value) and float(value).is_integer() and value >= (kind == "count")
    if kind == "positives":
        return isinstance(value, list) and bool(value) and all(number(v) and v > 0 for v in value)
    if not number(value):
        return False
    return {"number": True, "positive": value > 0, "non-negative": value >= 0,
            "fraction": 0 < value < 1}[kind]


def parse_option_pairs(items: list[str] | None, model: str | None = None) -> dict:
    """``KEY=VALUE`` pairs (VALUE as JSON when it parses, else as text) -> dict.

    Known keys are type-checked (:data:`_OPTION_TYPES`); unknown ones are left to the
    model's workflow, which names the options it takes.
    """
    from ..errors import ArgumentError, FogbayesError

    out = {}
    for item in items or []:
        key, sep, value = item.partition("=")
        if not sep or not key.strip():
            raise FogbayesError(f"option '{item}' is not KEY=VALUE", column="--option",
                                fix="write e.g. --option rate_window_s=30")
        key = key.strip().replace("-", "_")
        try:
            parsed = json.loads(value)
        except (json.JSONDecodeError, RecursionError):
            parsed = value
        kind = _OPTION_TYPES.get(key)
        if kind is not None and not _typed(key, parsed, kind):
            what, example = _KINDS[kind]
            raise ArgumentError(f"-O {key}={value}: {key} must be {what}", column="--option",
                                fix=f"write e.g. -O {key}={example}")
        if kind in ("integer", "count"):
            parsed = int(parsed)
        elif kind == "texts" and isinstance(parsed, str):  # one name: a list of one
            parsed = [parsed]
        if model == "arma" and key not in _ARMA_OPTIONS:
            raise ArgumentError(f"unknown option '{key}' for model arma", column="--option",
                                fix=f"use {', '.join(_ARMA_OPTIONS)}")
        out[key] = parsed
    return out


_KINDS = {  # kind -> (what it is, an example value)
    "text": ("a word", "paper"), "texts": ("a name or a JSON list of names", "temperature_2"),
    "text or null": ("a name or null", "temperature"), "bool": ("true or false", "true"),
    "integer": ("an integer >= 0", "2"), "count": ("an integer >= 1", "500"),
    "positive": ("a number > 0", "3"), "positive or null": ("a number > 0 or null", "2"),
    "non-negative": ("a number >= 0", "0.5"), "number": ("a number", "20"),
    "fraction": ("a number between 0 and 1", "0.9"),
    "positives": ("a JSON list of numbers > 0", "[1,10,100]"),
}


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
    json_out: str = typer.Option(None, "--json",
                                 help="Fit document to write ('-' = stdout); without it the "
                                      "result is only printed."),
    orders: str = typer.Option(None, "--orders", "--order",
                               help="Order(s): bias-t '3' or '1-4'; thermal '2,2' or '1-3,1-2'; "
                                    "composite 's1,s2,u0[,u1]' (three values: u1 = u0); "
                                    "'auto' selects by the RMS criterion."),
    bayes: bool = typer.Option(False, "--bayes", help="Also compute the posterior (NUTS)."),
    seed: int = typer.Option(0, help="Seed of the posterior sampler."),
    processing: str = typer.Option(None, help="thermal models: 'default' or 'paper' (paper 004 exactly)."),
    noise: str = typer.Option(None, help="Posterior noise model: ar | white | arma."),
    option: list[str] = typer.Option(None, "--option", "-O",
                                     help="Model option KEY=VALUE (repeatable), e.g. rate_window_s=30."),
    strict: bool = typer.Option(False, help="Exit with code 1 when the fit did not converge."),
    estimator: str = typer.Option(
        "ols", "--estimator",
        help="bias-t/thermal: 'ols' (least squares on 1 s blocks, paper 004) or 'gls' (the "
             "closed loop's fit with no step added: GLS under its noise model less the random "
             "walk, covariance under the full white + flicker + random-walk model; writes the "
             "loop document)."),
    time_unit: str = TIME_UNIT_OPT,
    quiet: bool = QUIET_OPT,
):
    """Fit a model to a recording, print the result and (with --json) write the fit document.

    The document holds the coefficients in the scaled basis (what 'fogbayes compensate' uses) and in the papers' raw form with standard errors, the processing, outlier counts, bias stability before/after (thermal models) and, with --bayes, posterior intervals and convergence.

    Examples:
      fogbayes fit run.csv --model thermal --json fit.json
      fogbayes fit run.csv -m bias-t --orders auto --json fit.json
      fogbayes fit run.csv -m thermal --orders 2,2 --bayes --json fit.json
      fogbayes fit chamber.csv -m thermal --processing paper --json fit.json
      fogbayes fit chamber.csv -m thermal --orders 2,1 --estimator gls --json fit.json
      fogbayes -q fit table.csv -m composite --json - > fit.json
      fogbayes fit flight.ulg -m bias-t --axis all --json fit.json   # then: export -f px4

    With several axes (--axis all or x,z for a gyro log, --column gx,gy,gz for a table) the
    document holds one fit document per axis under "axes" (docs/logs.md).
    """
    from ..workflow import workflow_for

    refuse_overwrite({"the recording": rec}, {"--json": json_out})
    wf = workflow_for(model)
    options = parse_option_pairs(option, model)
    for key, value in (("processing", processing), ("noise", noise)):
        if value is not None:
            options[key] = value
    axis, column = (reading_options()[k] for k in ("axis", "column"))
    gls = _gls_check(estimator, model, orders, bayes, options, axis, column)
    from ..data.logs.firmware import rate_warnings

    def fit_one(recording) -> dict:
        if gls:
            from ..loop.gls_fit import fit_gls

            return fit_gls(recording, model, orders, seed=seed)
        doc = wf.fit_recording(recording, model=model, orders=orders, bayes=bayes, seed=seed,
                               **options)
        more = rate_warnings(recording.meta.extra)  # a log's rates already corrected/rotated
        if more:
            doc["warnings"] = list(doc.get("warnings") or []) + more
        return doc

    docs, doc = fit_channels(rec, axis, column, {"time_unit": time_unit}, fit_one,
                             f"fitting {model}" + (" (posterior)" if bayes else ""))
    if json_out is not None:
        write_json(doc, json_out)
    for name, one in docs.items():
        tag = "" if name is None else f"[{name}] "
        if gls:
            from ..loop.gls_fit import summary_line as gls_line

            say(tag + gls_line(one))
        else:
            say(tag + summary_line(one))
            if bayes:  # asked for the posterior: say it, not only the least-squares line
                from .fit_summary import posterior_lines

                for line in posterior_lines(one):
                    say(tag + line)
        for warning in one.get("warnings") or []:  # e.g. not identifiable, gross errors
            say(f"{tag}warning: {warning}")
    if json_out is None:  # printed only: say how to keep it, since compensate needs the file
        say("not saved: add --json FIT.json to keep the calibration for 'fogbayes compensate'")
    converged = [one.get("calibration", {}).get("noise", {}).get("converged", False) if gls
                 else one.get("converged", False) for one in docs.values()]
    if strict and not all(converged):
        say("the fit did not converge (--strict)")
        raise typer.Exit(1)


def _gls_check(estimator: str, model: str, orders, bayes: bool, options: dict, axis,
               column: str) -> bool:
    """Whether ``--estimator`` asks for the GLS path; what that path cannot take is refused
    here, in one line each (it has the loop's own processing and no posterior)."""
    from ..errors import ArgumentError

    if estimator not in ("ols", "gls"):
        raise ArgumentError(f"--estimator {estimator!r} is not ols or gls", column="--estimator",
                            fix="use --estimator ols (default) or --estimator gls")
    if estimator == "ols":
        return False
    from ..loop.gls_fit import gls_orders

    gls_orders(model, orders)
    taken = [flag for flag, used in (("--bayes", bayes), ("--processing/--noise/-O", options),
                                     ("several axes", len(channels(axis, column)) > 1)) if used]
    if taken:
        raise ArgumentError(f"--estimator gls does not take {taken[0]}", column="--estimator",
                            fix="drop it, or use --estimator ols (--bayes gives the posterior "
                                "there); fit one axis at a time with --axis x")
    return True
