"""``fogbayes allan REC --json OUT``: Allan deviation with intervals and the five-term fit.

Wires :func:`fogbayes.allan.workflow.fit_recording` (canonical units), ``--plot`` the figure,
``--prior`` a datasheet prior (:mod:`fogbayes.inference.datasheet`) with ``--bayes``.
"""

from __future__ import annotations

from pathlib import Path

import typer

from ._app import app
from ._common import (QUIET_OPT, REC_ARG, TIME_UNIT_OPT, fit_channels, reading_options,
                      refuse_overwrite, say, write_json)

_TAUS = ("octave", "decade", "dense", "all")
_KINDS = ("oadev", "adev", "mdev", "tdev", "ohdev", "hdev", "totdev", "mtotdev", "ttotdev",
          "htotdev", "theo1", "theobr", "theoh")
_BIASED = ("totdev", "htotdev", "theo1")


def summary_lines(doc: dict) -> list[str]:
    """A few lines for people: method, each term with its 90 % interval."""
    fit = doc["fit"]
    out = [f"allan: n={doc['n']} fs={doc['fs']:g} Hz, {len(doc['tau'])} taus, "
           f"fit={fit['method']} converged={fit['converged']}"]
    extra = doc.get("deviation")
    if extra:
        bc = ", bias-corrected" if extra["bias_corrected"] else ""
        unit = "deg/h*s" if extra["kind"] in ("tdev", "ttotdev") else "deg/h"
        out.append(f"  {extra['kind']}{bc}: {len(extra['tau'])} taus, "
                   f"{extra['dev'][0]:.4g} {unit} at tau {extra['tau'][0]:.4g} s ... "
                   f"{extra['dev'][-1]:.4g} at {extra['tau'][-1]:.4g} s (under 'deviation')")
    for t in ("Q", "N", "B", "K", "R"):
        e = fit["terms"].get(t)
        if e is None:
            continue
        flag = "" if e.get("present", True) else "  (not supported: upper bound)"
        urad = (f"  = {e['value_urad']:.4g} urad" if "value_urad" in e else "")
        out.append(f"  {t} = {e['value']:.4g} [{e['low']:.4g}, {e['high']:.4g}] {e['unit']}"
                   f"{urad}{flag}")
    diag = fit.get("diagnostics", {})
    if diag.get("weights_settled") is False:
        out.append(f"  note: the GLS weights cycled between two solutions for {diag['passes']} "
                   "passes (terms that trade off at the longest taus, usually K and R); the "
                   "likelier one is shown: a longer record separates them")
    if diag.get("dispersion", 1.0) > 1.0:
        out.append(f"  note: the five-term model misfits this Allan curve (gof p = "
                   f"{diag['gof_p']:.2g}): every interval is widened by "
                   f"{diag['dispersion'] ** 0.5:.2g}x; plot it (--plot) before trusting it")
    prior = fit.get("prior")
    if prior:
        sheet = ", ".join(f"{t} {p['value']:.4g} {p['unit']} (90 % in "
                          f"[{p['value'] / p['looseness']:.3g}, "
                          f"{p['value'] * p['looseness']:.3g}])"
                          for t, p in prior["terms"].items())
        who = f" ({prior['sensor']})" if prior.get("sensor") else ""
        out.append(f"  prior: datasheet{who}: {sheet}")
    return out


@app.command()
def allan(
    rec: Path = REC_ARG,
    json_out: str = typer.Option(..., "--json", help="Result document to write ('-' = stdout)."),
    taus: str = typer.Option("octave", help="Tau grid: octave | decade | dense | all."),
    per_decade: int = typer.Option(20, help="Points per decade of the dense grid."),
    kind: str = typer.Option(
        "oadev", "--kind",
        help="Also compute this deviation, stored under 'deviation' with 90 % intervals (the "
             "noise fit stays on the OADEV): " + " | ".join(_KINDS) + ". htotdev (Hadamard "
             "total) ignores a rate ramp; theo1 reports tau = 0.75 m tau0; theobr is Theo1 "
             "times the record's AVAR/Theo1 (Stable32); theoh is OADEV below 20 % of the "
             "record, theobr above."),
    bias_corrected: bool = typer.Option(
        False, "--bias-corrected",
        help="With --kind " + ", ".join(_BIASED) + ": remove the estimator's bias for the "
             "identified noise type (Stable32's HTOTDEV factors; Theo1 to the Allan variance)."),
    bayes: bool = typer.Option(False, "--bayes",
                               help="NumPyro posterior with term selection (slower)."),
    seed: int = typer.Option(0, help="Seed of the posterior sampler."),
    prior: Path = typer.Option(None, "--prior",
                               help="Datasheet prior (written by 'fogbayes prior'), with "
                                    "--bayes: log-normal priors on the terms it gives."),
    plot: Path = typer.Option(None, "--plot", help="Also write the log-log ADEV figure (PNG/PDF)."),
    time_unit: str = TIME_UNIT_OPT,
    quiet: bool = QUIET_OPT,
):
    """Allan deviation with 90 % intervals and the five-term noise fit (Q, N, B, K, R).

    The JSON document holds tau, the overlapping ADEV with its 90 % interval, and each noise term with its interval, in canonical units (N deg/sqrt(h), B deg/h, K deg/h^1.5, R deg/h^2, Q arcsec and urad) whatever the input unit.

    Examples:
      fogbayes allan static.csv --json adev.json --plot adev.png
      fogbayes allan gyro.csv --output-unit deg/s --taus dense --bayes \\
          --json av.json
      fogbayes -q allan static.csv --json - > adev.json
      fogbayes allan flight.ulg --axis all --json adev.json --plot adev.png
      fogbayes prior --arw 0.05 --bias-instability 0.5 --json sheet.json
      fogbayes allan short.csv --bayes --prior sheet.json --json av.json

    With several axes (--axis all or x,z for a gyro log, --column gx,gy,gz for a table) the
    document holds one Allan document per axis under "axes" (docs/logs.md).
    """
    from ..errors import FogbayesError
    from ..data.atomic import all_or_none, atomic_path
    from ..allan.workflow import fit_recording

    refuse_overwrite({"the recording": rec, "the --prior document": prior},
                     {"--json": json_out, "--plot": plot})
    sheet = None
    if prior is not None:
        if not bayes:
            raise FogbayesError("--prior needs --bayes: the least-squares fit has no prior",
                                column="--prior",
                                fix="add --bayes (the datasheet prior enters the posterior), "
                                    "or leave --prior out")
        from ..inference.datasheet import read_prior

        sheet = read_prior(prior)
    if kind not in _KINDS:
        raise FogbayesError(f"unknown deviation '{kind}'", column="--kind",
                            fix=f"use one of {', '.join(_KINDS)}")
    if bias_corrected and kind not in _BIASED:
        raise FogbayesError(f"--bias-corrected applies to {', '.join(_BIASED)}, not {kind}",
                            column="--bias-corrected",
                            fix=f"add --kind {_BIASED[1]} (or another of them), or leave "
                                "--bias-corrected out")
    if taus not in _TAUS:
        raise FogbayesError(f"unknown tau grid '{taus}'", column="--taus",
                            fix=f"use one of {', '.join(_TAUS)}")
    if per_decade < 1:
        raise FogbayesError(f"--per-decade is {per_decade}; it must be >= 1",
                            column="--per-decade", fix="give e.g. --per-decade 20")
    if plot is not None:
        from ..plot.style import figure_format

        figure_format(plot)  # an unknown extension fails now, not after the fit
    axis, column = (reading_options()[k] for k in ("axis", "column"))
    docs, doc = fit_channels(
        rec, axis, column, {"time_unit": time_unit},
        lambda r: fit_recording(r, model="allan", bayes=bayes, seed=seed, taus=taus,
                                per_decade=per_decade, prior=sheet, kind=kind,
                                bias_corrected=bias_corrected),
        "Allan deviation and noise fit" + (" (posterior)" if bayes else ""))
    with all_or_none():  # --json and --plot appear both or neither
        write_json(doc, json_out)
        if plot is not None:
            from ..plot.allan import allan_figure

            fig = allan_figure(doc)
            with atomic_path(plot) as tmp:  # the suffix is kept: PNG or PDF from the name
                fig.savefig(tmp, dpi=150)
    for name, one in docs.items():
        for line in summary_lines(one):
            say(line if name is None else f"[{name}] {line}")
    if plot is not None:
        say(f"wrote {plot}")
