"""``fogbayes arma REC``: ARMA drift model of a static recording (paper 002, section 2)."""

from __future__ import annotations

from pathlib import Path

import typer

from ._app import app
from ._common import (QUIET_OPT, REC_ARG, TIME_UNIT_OPT, load_recording, progress,
                      refuse_overwrite, say, write_json)


@app.command()
def arma(
    rec_path: Path = REC_ARG,
    json_out: str = typer.Option(..., "--json", help="Result document to write ('-' = stdout)."),
    decimate: int = typer.Option(1, help="Average blocks of K samples first (paper: 10 Hz)."),
    detrend: int = typer.Option(1, help="Order of the polynomial trend removed first "
                                        "(0 = mean only)."),
    candidates: str = typer.Option("paper", help="Orders to compare: 'paper' (AR(1), AR(2), "
                                   "AR(3), ARMA(1,1), ARMA(2,1)), 'grid' (p, q <= 3), "
                                   "'grid:P,Q' or 'p,q;p,q;...'."),
    criterion: str = typer.Option("bic", help="Order selection criterion: bic or aic "
                                  "(the paper's AIC over-fits nested candidates)."),
    lags: int = typer.Option(None, help="Ljung-Box lags (default min(20, n/5))."),
    bayes: bool = typer.Option(False, "--bayes", help="Also NumPyro posteriors with WAIC/LOO "
                               "for every candidate (n <= 20000)."),
    seed: int = typer.Option(0, help="Random seed of the Bayesian sampler."),
    plot: Path = typer.Option(None, "--plot", help="Write a PNG: ACF/PACF, one-step "
                              "prediction, filtered signal and removed noise."),
    time_unit: str = TIME_UNIT_OPT,
    quiet: bool = QUIET_OPT,
):
    """Identify, fit and check an ARMA model of the gyro drift; filter the record.

    The JSON document holds the selected order, every candidate's AIC/BIC/log-likelihood, the parameters in the paper's sign convention (x_t = sum phi_i x_{t-i} + a_t - sum theta_j a_{t-j}) with standard errors, in the output unit of the recording, and the whiteness of the residuals (rho_a2, rho_ax3, Ljung-Box p).

    Examples:
      fogbayes arma static.csv --decimate 10 --json arma.json --plot arma.png
      fogbayes arma static.csv --candidates grid --criterion aic --json arma.json
      fogbayes -q arma static.csv --output-unit deg/s --json - > arma.json
    """
    from ..data.atomic import all_or_none, atomic_path
    from ..errors import ArgumentError, about_file
    from ..arma.workflow import analyse_recording

    refuse_overwrite({"the recording": rec_path}, {"--json": json_out, "--plot": plot})
    for flag, value, least in (("--decimate", decimate, 1), ("--detrend", detrend, 0),
                               ("--lags", lags, 1)):
        if value is not None and value < least:
            raise ArgumentError(f"{flag} is {value}; it must be an integer >= {least}",
                                column=flag, fix=f"give {flag} {least} or more"
                                + (" (or leave it out: min(20, n/5))" if flag == "--lags" else ""))
    if plot is not None:
        from ..plot.style import figure_format

        figure_format(plot)  # an unknown extension fails now, not after the fit
    rec = load_recording(rec_path, time_unit=time_unit)
    with progress("fitting ARMA candidates"), about_file(rec_path):
        result = analyse_recording(rec, decimate=decimate, detrend_order=detrend,
                                   candidates=candidates, criterion=criterion, lags=lags,
                                   bayes=bayes, seed=seed)
    doc = result.document
    doc["file"] = str(rec_path)
    with all_or_none():  # --json and --plot appear both or neither
        write_json(doc, json_out)
        if plot is not None:
            from ..plot.arma import analysis_figure

            with atomic_path(plot) as tmp:  # the suffix is kept: the format from the name
                analysis_figure(result).savefig(tmp, dpi=120)
    if plot is not None:
        say(f"wrote {plot}")
    w = doc["whiteness"]
    say(f"selected {doc['selected']} by {criterion.upper()}; converged={doc['converged']}; "
        f"Ljung-Box p={w['ljung_box_p']:.3g}; white={w['white']}")
