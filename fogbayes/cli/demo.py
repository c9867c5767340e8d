"""``fogbayes demo``: the whole story on built-in simulated data, no files needed."""

from __future__ import annotations

from pathlib import Path

import typer

from ._app import app
from ._common import QUIET_OPT, progress, refuse_overwrite, say, write_json


def summary_document(result) -> dict:
    """The ``--json`` document: files written and, per model, convergence, orders and the
    bias stability before/after on each window (the numbers the printed summary shows)."""
    models = {}
    for model, doc in result.fits.items():
        models[model] = {"converged": doc.get("converged"),
                         "spec": doc["params"]["spec"],
                         "stability": doc["metrics"]["full"]["stability"]}
    return {"report": str(result.report), "recording": str(result.recording), "models": models}


@app.command()
def demo(
    out: Path = typer.Option(Path("fogbayes_demo"), "--out", "-o",
                             help="Folder for the report and the simulated recording."),
    seed: int = typer.Option(0, help="Random seed of the simulated test."),
    duration: float = typer.Option(None, help="Test length in s (default: the 6.3 h thermal test)."),
    fs: float = typer.Option(None, help="Sample rate in Hz (default 10)."),
    json_out: str = typer.Option(None, "--json", help="Also write a summary document (files, "
                                 "bias stability before/after per model) ('-' = stdout)."),
    quiet: bool = QUIET_OPT,
):
    """Simulate a thermal-chamber test, fit, compensate and write a report.

    No arguments and no files are needed: the test is simulated (quadratic bias in temperature plus a Shupe temperature-rate term, FOG-like noise), fitted with bias-t and thermal, compensated, and written up in OUT/report.html next to the recording OUT/demo_recording.csv, which the other commands can read.

    Examples:
      fogbayes demo
      fogbayes demo --out demo_out --seed 3
      fogbayes -q demo --duration 7200 --fs 1 --json - > demo.json
    """
    from ..workflow.demo import run_demo

    refuse_overwrite({}, {"--out": out / "report.html",  # first: a bad folder names --out
                          "the recording": out / "demo_recording.csv", "--json": json_out})
    from ..data.atomic import all_or_none

    with all_or_none():  # the report, the recording and --json appear all or none
        with progress("fogbayes demo", total=5) as advance:
            def step(msg):
                say(msg)
                advance()

            result = run_demo(out, seed=seed, duration=duration, fs=fs, step=step)
        if json_out:
            write_json(summary_document(result), json_out)
    if json_out == "-":  # stdout holds the JSON document only
        say(result.summary)
    else:
        typer.echo(result.summary)
