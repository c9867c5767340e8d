"""``fogbayes simulate SCENARIO --out FILE``: write a simulated Recording with known truth."""

from __future__ import annotations

import json
import math
from pathlib import Path

import typer

from ._app import app
from ._common import QUIET_OPT, progress, refuse_overwrite, say, write_json


@app.command()
def simulate(
    scenario: str = typer.Argument("thermal", help="Scenario name; --list shows them."),
    out: Path = typer.Option(None, "--out", "-o", help="Recording file to write (.csv, .parquet, .npz)."),
    seed: int = typer.Option(0, help="Random seed (same seed, same data)."),
    fs: float = typer.Option(None, help="Sample rate in Hz (default: the scenario's)."),
    duration: float = typer.Option(None, help="Duration in s (default: the scenario's)."),
    effect: list[str] = typer.Option(
        None, "--effect",
        help="Add an effect: NAME or NAME='{\"param\": value}' (repeatable); see --list."),
    truth: str = typer.Option(None, "--truth", "--json",
                              help="Also write the true parameters as a JSON document "
                                   "('-' = stdout)."),
    list_: bool = typer.Option(False, "--list", help="List scenarios and effects, then exit."),
    quiet: bool = QUIET_OPT,
):
    """Simulate a FOG test with known truth and write it as a recording file.

    Scenarios: thermal (6.3 h chamber test), paper004 (paper 004's verification profile), paper000 (paper 000's rate table, output in V), ratetable, static. Effects (temperature_rate, step, periodic, ...) are added by name with --effect; --list shows them all. The same seed gives the same data.

    Examples:
      fogbayes simulate thermal --seed 3 --out run.csv --truth truth.json
      fogbayes simulate thermal --effect step --effect periodic --out run.csv
      fogbayes simulate thermal --effect step='{"size": 0.5}' --out step.csv
      fogbayes simulate paper004 --fs 1 --out p004.parquet
      fogbayes simulate --list
    """
    from ..data import save
    from ..errors import ArgumentError, FogbayesError
    from ..simulate.profiles import MAX_SAMPLES
    from ..simulate import EFFECTS, SCENARIOS
    from ..simulate import simulate as run

    if list_:
        typer.echo("scenarios:")
        for name, text in SCENARIOS.items():
            typer.echo(f"  {name:10s} {text}")
        typer.echo("effects (--effect NAME or NAME='{json params}'):")
        for name, spec in EFFECTS.items():
            typer.echo(f"  {name:26s} {getattr(spec, 'description', spec)}")
        return
    if out is None:
        raise FogbayesError("no output file given", column="--out",
                            fix="add --out run.csv (or .parquet / .npz)")
    refuse_overwrite({}, {"--out": out, "--truth": truth})
    for flag, value in (("--fs", fs), ("--duration", duration)):
        if value is not None and not (math.isfinite(value) and value > 0):
            raise ArgumentError(f"{flag} is {value:g}; it must be a finite number > 0", column=flag,
                                fix=f"give {flag} > 0 or leave it out for the scenario's default")
    if fs is not None and duration is not None and fs * duration > MAX_SAMPLES:
        raise ArgumentError(f"--fs {fs:g} for --duration {duration:g} s is {fs * duration:.3g} "
                            f"samples ({fs * duration * 8 / 1e9:.3g} GB per column), more than "
                            f"the {MAX_SAMPLES:.0e} a simulated record may have",
                            column="--duration", fix="lower --duration or --fs")
    effects = {}
    for item in effect or []:
        name, _, params = item.partition("=")
        try:
            effects[name.strip()] = json.loads(params) if params else {}
        except (json.JSONDecodeError, RecursionError) as exc:
            msg = getattr(exc, "msg", "nested too deeply")
            raise FogbayesError(f"parameters of effect '{name}' are not valid JSON ({msg})",
                                column="--effect", fix="write e.g. --effect step='{\"size\": 0.5}'") from None
        if not isinstance(effects[name.strip()], dict):
            raise ArgumentError(f"parameters of effect '{name}' are {params}, not a JSON object",
                                column="--effect", fix="write e.g. --effect step='{\"size\": 0.5}'")
    from ..data.atomic import all_or_none

    with all_or_none():  # --out and --truth appear both or neither
        with progress(f"simulating {scenario}"):
            sim = run(scenario, seed=seed, fs=fs, duration=duration, effects=effects or None)
            save(sim.recording, out)
        if truth is not None:
            write_json(sim.truth.params, truth, tell=False)
    say(f"wrote {out}: {sim.recording!r}")
    if truth is not None and truth != "-":
        say(f"wrote {truth}")
