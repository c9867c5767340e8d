"""Fleets: fit, compensate, loop or report many recordings, in-process or on Dask.

* :func:`run_batch` -- every recording of a folder through one task; ``OUT/summary.json``
  (:mod:`.fleet`);
* :func:`run_one` -- one recording -> its output files and summary row (:mod:`.jobs`);
* :func:`run_tasks` -- the engines: ``"local"`` (serial, in-process) and ``"dask"`` (a
  ``LocalCluster`` we start, or an existing scheduler by ``address``) (:mod:`.engine`;
  why Dask rather than Ray is written there);
* :func:`fit_vectorized` -- ``bias-t``/``thermal`` fits of same-shape recordings with one
  ``jit(vmap)`` least-squares call (:mod:`.vectorized`; what is and is not vectorised).

Example:
    >>> from fogbayes.batch import run_batch                      # doctest: +SKIP
    >>> s = run_batch("runs/", model="bias-t", out="fits/", engine="dask", workers=2)
    >>> [(r["file"], r["status"]) for r in s["rows"]]
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
