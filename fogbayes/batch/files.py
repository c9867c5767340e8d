"""Which recordings a fleet run takes, and the error for an unusable fleet.

``find_recordings(DIR, pattern)``: files of ``DIR`` (not subfolders) matching the comma-separated
globs, sorted by name; ``*.compensated.csv`` and ``.<stem>.tmp-*`` (:mod:`fogbayes.data.atomic`)
are skipped.
"""

from __future__ import annotations

from pathlib import Path

from ..data.atomic import is_temp_name
from ..errors import FogbayesError

#: What a batch task can be asked to do to each recording.
TASKS = ("fit", "compensate", "loop", "report")
#: Outputs of an earlier run that a pattern like ``*.csv`` would otherwise pick up again.
_OUTPUT_SUFFIXES = (".compensated.csv",)


class FleetError(FogbayesError):
    """A fleet run cannot start: no such folder, no recordings, a bad engine or option."""


def find_recordings(folder: str | Path, pattern: str = "*.csv") -> list[Path]:
    """The recordings in ``folder`` matching ``pattern`` (``"*.csv,*.parquet"``), sorted."""
    folder = Path(folder)
    if not folder.is_dir():
        what = "is a file, not a folder" if folder.exists() else "no such folder"
        raise FleetError(what, file=str(folder),
                         fix=f"pass the folder that holds the recordings, or make one: mkdir "
                             f"{folder} && fogbayes simulate thermal --seed 1 --out "
                             f"{folder / 'unit1.csv'}")
    patterns = [p.strip() for p in str(pattern).split(",") if p.strip()]
    if not patterns:
        raise FleetError("empty --pattern", column="--pattern", fix="use e.g. --pattern '*.csv'")
    found = {p for pat in patterns for p in folder.glob(pat)
             if p.is_file() and not p.name.endswith(_OUTPUT_SUFFIXES)
             and not is_temp_name(p.name)}
    if not found:
        raise FleetError(f"no recordings match '{pattern}'", file=str(folder),
                         fix="put .csv/.parquet/.npz recordings there or change --pattern")
    files = sorted(found, key=lambda p: p.name)
    stems: dict[str, Path] = {}
    for f in files:  # outputs are named after the stem: two recordings must not share one
        if f.stem in stems:
            raise FleetError(f"'{stems[f.stem].name}' and '{f.name}' would write the same "
                             f"outputs ({f.stem}.*)", file=str(folder),
                             fix="rename one, or narrow --pattern to one file type")
        stems[f.stem] = f
    return files


def check_task(task: str, model: str) -> None:
    """Refuse an unknown task or model before any work (or any cluster) starts."""
    from ..workflow import MODULES as MODELS

    if task not in TASKS:
        raise FleetError(f"unknown task '{task}'", column="--task",
                         fix=f"use one of {', '.join(TASKS)}")
    if model not in MODELS:
        raise FleetError(f"unknown model '{model}'", column="--model",
                         fix=f"use one of {', '.join(MODELS)}")
    if task == "compensate" and model in ("allan", "arma"):
        raise FleetError(f"model '{model}' describes noise: there is nothing to compensate",
                         column="--model", fix="use --task fit, or a bias-t/thermal/composite model")
    if task == "loop" and model == "arma":
        raise FleetError("the closed loop does not start from 'arma'", column="--model",
                         fix="use bias-t, thermal, composite or allan")
