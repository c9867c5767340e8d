"""Helpers shared by the subcommands: loading recordings, writing JSON, progress."""

from __future__ import annotations

import json
import sys
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import typer
from rich.console import Console

from .._json import (
    to_jsonable,  # the one sanitiser (fogbayes/_json.py), re-exported here
)
from ..data import Recording, load

#: Messages for people go to stderr so that `--json -` keeps stdout clean.
console = Console(stderr=True)
QUIET = {"on": False}

REC_ARG = typer.Argument(..., help="Recording file (.csv, .parquet or .npz).", show_default=False)

#: Options that say how to read a recording; the same names and help on every command.
_INPUT = "Reading the recording"
COLUMN_OPT = typer.Option("output", "--column", help="Gyro output column.",
                          rich_help_panel=_INPUT)
TIME_COLUMN_OPT = typer.Option("time", "--time-column", help="Time column (s).",
                               rich_help_panel=_INPUT)
OUTPUT_UNIT_OPT = typer.Option(None, "--output-unit",
                               help="Output unit: deg/h, deg/s, rad/s, V, mV or Hz "
                                    "(default: the file's '# unit:' line, else deg/h).",
                               rich_help_panel=_INPUT, show_default=False)
SCALE_FACTOR_OPT = typer.Option(None, "--scale-factor",
                                help="Raw units per deg/s, for V/mV/Hz outputs.",
                                rich_help_panel=_INPUT, show_default=False)
TEMPERATURE_OPT = typer.Option(None, "--temperature",
                               help="Temperature column (repeatable; first = main). Default: "
                                    "every 'temperature', 'temperature_<k>' column.",
                               rich_help_panel=_INPUT, show_default=False)
INPUT_RATE_OPT = typer.Option("input_rate", "--input-rate-column",
                              help="Reference-rate column (deg/s), used when present.",
                              rich_help_panel=_INPUT)


def _quiet(value: bool) -> bool:
    """``--quiet`` after a subcommand: the same switch as ``fogbayes --quiet``."""
    if value:
        QUIET["on"] = True
    return value


#: ``-q/--quiet``, accepted on every subcommand as well as on the root command.
QUIET_OPT = typer.Option(False, "--quiet", "-q", callback=_quiet,
                         help="No progress bars or status lines on stderr; results only.")


def load_recording(path: Path, *, column: str = "output", time_column: str = "time",
                   output_unit: str | None = None, scale_factor: float | None = None,
                   temperature: list[str] | None = None,
                   input_rate: str = "input_rate") -> Recording:
    """Load a Recording with the command line's column/unit overrides."""
    return load(path, time=time_column, output=column, unit=output_unit,
                scale_factor=scale_factor, temperature=temperature or None,
                input_rate=input_rate)


def write_json(obj: Any, out: Path | str) -> None:
    """Write ``obj`` as JSON to ``out``; ``-`` means stdout."""
    text = json.dumps(to_jsonable(obj), indent=2)
    if str(out) == "-":
        sys.stdout.write(text + "\n")
    else:
        Path(out).parent.mkdir(parents=True, exist_ok=True)
        Path(out).write_text(text + "\n")
        say(f"wrote {out}")


def say(msg: str) -> None:
    """Print a status line to stderr unless --quiet."""
    if not QUIET["on"]:
        console.print(msg, markup=False, highlight=False, soft_wrap=True)


@contextmanager
def progress(description: str, total: int | None = None):
    """A rich progress bar on stderr (silent with --quiet); yields an ``advance`` callable."""
    from rich.progress import (BarColumn, Progress, SpinnerColumn, TextColumn,
                               TimeElapsedColumn)

    if QUIET["on"]:
        yield lambda n=1: None
        return
    cols = [SpinnerColumn(), TextColumn("{task.description}"), BarColumn(), TimeElapsedColumn()]
    with Progress(*cols, console=console, transient=True) as bar:
        task = bar.add_task(description, total=total)
        yield lambda n=1: bar.advance(task, n)
