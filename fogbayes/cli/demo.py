"""``fogbayes demo``: the whole story on built-in simulated data, no files needed."""

from __future__ import annotations

from pathlib import Path

import typer

from ._app import app
from ._common import progress, say


@app.command()
def demo(
    out: Path = typer.Option(Path("fogbayes_demo"), "--out", "-o", help="Folder for the report and data."),
    seed: int = typer.Option(0, help="Random seed of the simulated test."),
    duration: float = typer.Option(None, help="Test length in s (default: the 6.3 h thermal test)."),
    fs: float = typer.Option(None, help="Sample rate in Hz (default 10)."),
):
    """Simulate a thermal-chamber test, fit, compensate and write a report.

    Example: fogbayes demo --out demo_out
    """
    from ..demo import run_demo

    with progress("fogbayes demo", total=5) as advance:
        def step(msg):
            say(msg)
            advance()

        result = run_demo(out, seed=seed, duration=duration, fs=fs, step=step)
    typer.echo(result.summary)
