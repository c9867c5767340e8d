"""``fogbayes simulate SCENARIO --out FILE``: write a simulated Recording with known truth."""

from __future__ import annotations

import json
from pathlib import Path

import typer

from ._app import app
from ._common import say, write_json


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
    truth: Path = typer.Option(None, help="Also write the true parameters as JSON."),
    list_: bool = typer.Option(False, "--list", help="List scenarios and effects, then exit."),
):
    """Simulate a FOG test with known truth and write it as a recording file.

    Example: fogbayes simulate thermal --seed 3 --effect step --out run.csv --truth truth.json
    """
    from ..data import save
    from ..errors import FogbayesError
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
    effects = {}
    for item in effect or []:
        name, _, params = item.partition("=")
        try:
            effects[name.strip()] = json.loads(params) if params else {}
        except json.JSONDecodeError as exc:
            raise FogbayesError(f"parameters of effect '{name}' are not valid JSON ({exc.msg})",
                                column="--effect", fix="write e.g. --effect step='{\"size\": 0.5}'") from None
    sim = run(scenario, seed=seed, fs=fs, duration=duration, effects=effects or None)
    save(sim.recording, out)
    say(f"wrote {out}: {sim.recording!r}")
    if truth is not None:
        write_json(sim.truth.params, truth)
