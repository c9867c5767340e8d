"""Fleets: fit, compensate, loop or report many recordings, in-process or on Dask.

:func:`run_batch` (:mod:`.fleet`, ``OUT/summary.json``), :func:`run_one` (:mod:`.jobs`),
:func:`run_tasks` (:mod:`.engine`: ``"local"`` or ``"dask"``), :func:`fit_vectorized`
(:mod:`.vectorized`: same-shape ``bias-t``/``thermal`` fits in one batched solve).
"""

from .engine import ENGINES, dask_client, run_tasks
from .files import TASKS, FleetError, find_recordings
from .fleet import run_batch
from .jobs import JobOptions, run_one
from .vectorized import fit_vectorized

__all__ = [
           "ENGINES",
           "TASKS",
           "FleetError",
           "JobOptions",
           "dask_client",
           "find_recordings",
           "fit_vectorized",
           "run_batch",
           "run_one",
           "run_tasks",
]
