"""Helpers shared by the subcommands: loading recordings, writing JSON, progress."""

from __future__ import annotations

import json
import math
import sys
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np
import typer
from rich.console import Console

from ..data import Recording, load

#: Messages for people go to stderr so that `--json -` keeps stdout clean.
console = Console(stderr=True)
QUIET = {"on": False}

REC_ARG = typer.Argument(..., help="Recording file (.csv, .parquet or .npz).", show_default=False)


def load_recording(path: Path, *, column: str = "output", time_column: str = "time",
                   output_unit: str | None = None, scale_factor: float | None = None,
                   temperature: list[str] | None = None) -> Recording:
    """Load a Recording with the command line's column/unit overrides."""
    return load(path, time=time_column, output=column, unit=output_unit,
                scale_factor=scale_factor, temperature=temperature or None)


def to_jsonable(obj: Any) -> Any:
    """NumPy/JAX scalars and arrays to plain Python; NaN/inf to None (valid JSON)."""
    if isinstance(obj, dict):
        return {str(k): to_jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [to_jsonable(v) for v in obj]
    if hasattr(obj, "_asdict"):
        return to_jsonable(obj._asdict())
    if hasattr(obj, "tolist") and not isinstance(obj, (str, bytes)):
        return to_jsonable(obj.tolist())
    if isinstance(obj, (bool, np.bool_)):
        return bool(obj)
    if isinstance(obj, (int, np.integer)):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        f = float(obj)
        return f if math.isfinite(f) else None
    return obj


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
    from rich.progress import BarColumn, Progress, SpinnerColumn, TextColumn, TimeElapsedColumn

    if QUIET["on"]:
        yield lambda n=1: None
        return
    cols = [SpinnerColumn(), TextColumn("{task.description}"), BarColumn(), TimeElapsedColumn()]
    with Progress(*cols, console=console, transient=True) as bar:
        task = bar.add_task(description, total=total)
        yield lambda n=1: bar.advance(task, n)
