"""``fogbayes loop REC --model NAME [--json OUT] [--compensated OUT.csv] [--report OUT.html]``: the closed loop.

Runs :func:`fogbayes.loop.run_loop` (at most ``--max-steps``) and writes the outputs asked for
(at least one), all or none: the docs/DESIGN.md JSON, the compensated CSV (``time``, ``output``
or ``rate`` for ``composite``, ``outlier``), the HTML report.
"""

from __future__ import annotations

from pathlib import Path

import typer

from ._app import app
from ._common import (QUIET_OPT, REC_ARG, TIME_UNIT_OPT, load_recording, refuse_overwrite,
                      say, write_json)
from .loop_progress import loop_progress

#: Fewer samples than this give a loop without power that looks like a clean result:
#: refused (the residual whiteness tests use up to 20 lags, 5 samples a lag).
LOOP_MIN_SAMPLES = 100


def undecided(steps) -> list[str]:
    """One line per step whose duel the data could not decide, with the way out when a
    chamber programme can decide it (docs/plan.md)."""
    out = []
    for step in steps:
        rows = step.evidence.get("alternatives", [])
        alts = [a["effect"] for a in rows]
        if alts:  # the loop marks the duels a chamber programme could decide
            hint = (" (fogbayes plan-chamber proposes a chamber programme that separates them)"
                    if all(a.get("separable_by_programme") for a in rows) else "")
            out.append(f"undecided: {step.effect} kept (fewer searched parameters); the data "
                       f"cannot tell it from {', '.join(alts)}{hint}")
    return out

@app.command(name="loop")
def loop(
    rec_path: Path = REC_ARG,
    model: str = typer.Option(..., "--model", "-m",
                              help="Base model: bias-t | thermal | composite | allan."),
    json_out: str = typer.Option(None, "--json", show_default=False,
                                 help="Loop document to write ('-' = stdout). Not written "
                                      "unless asked for, as --compensated and --report; "
                                      "give at least one."),
    compensated: Path = typer.Option(None, "--compensated", show_default=False,
                                     help="Compensated CSV to write (every input row)."),
    max_steps: int = typer.Option(5, "--max-steps", min=0, help="Add at most this many effects."),
    effect: list[str] = typer.Option(
        None, "--effect", show_default=False, metavar="NAME",
        help="Declare an effect (repeatable): its terms join the base model before the "
             "search, its searched parameter chosen as the loop's; with --max-steps 0, "
             "the base model plus the declared effects."),
    report: Path = typer.Option(None, "--report", show_default=False,
                                help="HTML report of the loop to write."),
    orders: str = typer.Option(None, "--orders", "--order",
                               help="Base orders: bias-t 'n' (default 3); thermal 'n' or "
                                    "'n,m' (T, dT/dt; default 2,2); composite "
                                    "'s1,s2,u0[,u1]' as fit's (three values: u1 = u0; u1 "
                                    "'-': no U1(T) t drift; default 0,0,2,-)."),
    alpha: float = typer.Option(0.01, help="Family-wise false-effect level of each step."),
    seed: int = typer.Option(0, help="Seed of the bootstrap calibration and ELPD draws."),
    noise_prior: Path = typer.Option(
        None, "--noise-prior",
        help="Cap the random walk by a static run: a 'fogbayes allan --json' document "
             "(its K interval's upper end), a 'fogbayes prior' datasheet (K x looseness) "
             "or {\"K\": value} in deg/h^1.5."),
    time_unit: str = TIME_UNIT_OPT,
    quiet: bool = QUIET_OPT,
):
    """Run fit -> diagnose -> add effect -> refit until nothing more is supported.

    Each step adds the candidate effect (temperature rate, gradient, hysteresis, time drift, step, periodic, ...) that the evidence supports, calibrated so that clean data adds nothing; structure no candidate explains is listed as unexplained.

    Writes what --json, --compensated and --report ask for (at least one), nothing else.

    Examples:
      fogbayes loop chamber.csv -m bias-t --report loop.html
      fogbayes loop chamber.csv --model bias-t --json loop.json \\
          --compensated comp.csv --report loop.html
      fogbayes loop table.csv -m composite --max-steps 3 \\
          --json loop.json --compensated rates.csv
      fogbayes -q loop chamber.csv -m bias-t --json - --compensated comp.csv
      fogbayes allan static.csv --json static.json
      fogbayes loop chamber.csv -m bias-t --noise-prior static.json \\
          --json loop.json --compensated comp.csv
      fogbayes loop chamber.csv -m bias-t --max-steps 0 --effect temperature_rate \\
          --json fit.json
    """
    from ..data.atomic import all_or_none
    from ..data.io import write_csv_mixed
    from ..errors import FogbayesError, TooShortError, about_file
    from ..loop import run_loop

    refuse_overwrite({"the recording": rec_path, "the --noise-prior document": noise_prior},
                     {"--json": json_out, "--compensated": compensated, "--report": report})
    if json_out is None and compensated is None and report is None:
        raise FogbayesError("nothing to write: the loop writes what --json, --compensated "
                            "and --report ask for", column="--report",
                            fix=f"add e.g. --report {rec_path.stem}_loop.html (or --json "
                                "loop.json, --compensated comp.csv)")
    from ..loop.declared import check_declared

    declared = check_declared(effect, model, where="--effect")
    if not 0.0 < alpha < 0.5:
        raise FogbayesError(f"alpha={alpha} is outside (0, 0.5)", column="--alpha",
                            fix="use e.g. --alpha 0.01")
    prior = None
    if noise_prior is not None:
        from ..loop.noise_prior import read_noise_prior

        prior = read_noise_prior(noise_prior)
    rec = load_recording(rec_path, time_unit=time_unit)
    if rec.n < LOOP_MIN_SAMPLES:
        raise TooShortError(f"the closed loop needs at least {LOOP_MIN_SAMPLES} samples (20 "
                            f"blocks or more, residual tests over 20 lags), the recording has "
                            f"{rec.n}", file=str(rec_path),
                            fix=f"give a recording of {LOOP_MIN_SAMPLES} samples or more "
                                "(effects need several cycles of their driver: hours of data)")
    with loop_progress(f"loop {rec_path.name}", max_steps), about_file(rec_path):
        res = run_loop(rec, model, orders=orders, max_steps=max_steps, alpha=alpha, seed=seed,
                       noise_prior=prior, declared=declared)
    with all_or_none():  # a report that fails leaves no JSON or CSV behind
        if report is not None:
            from ..render.loop import loop_report

            loop_report(res, report, title=f"Closed loop: {rec_path.name}", rec=rec)
        if compensated is not None:
            write_csv_mixed(compensated, res.compensated)
        if json_out is not None:
            write_json(res.to_json(), json_out, tell=False)
    for out in (json_out, compensated, report):
        if out is not None and str(out) != "-":
            say(f"wrote {out}")
    if prior is not None:
        say(f"noise prior: random walk K <= {prior.k_max:.4g} deg/h^1.5 ({prior.source})")
    from ..render.effects import effect_phrase

    added = "; ".join(effect_phrase(s.effect, s.detail, s.covariates)
                      + (" (declared)" if s.evidence.get("declared") else "")
                      for s in res.steps) or "nothing"
    reason = res.stop.reason
    if res.effects and reason.startswith("no candidate"):  # after additions: none *further*
        reason = "no further" + reason[len("no"):]
    say(f"{model}: added {added}; 10 s RMS {res.initial.rms:.4g} -> {res.final.rms:.4g} deg/h; "
        f"stopped: {reason}")
    from ..loop.noise_model import sentence

    say(sentence(res.fit, res.noise_selection).split(";")[0])
    for r in (res.holdout or {}).get("not_kept", []):
        say(f"not kept: {r['effect']} (supported, but held-out time blocks predicted worse)")
    for w in res.warnings:
        say(f"warning: {w}")
    for line in undecided(res.steps):
        say(line)
    if res.unexplained:  # structure no candidate names: say so where the user looks first
        kinds = sorted({u["kind"] for u in res.unexplained})
        say(f"unexplained: {', '.join(kinds)} (see 'unexplained' in the JSON)")
