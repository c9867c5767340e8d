"""Test configuration: strict numerics and access to the measured data in ../shared.

float64 is switched on by importing fogbayes (fogbayes._config); we import it here so
every test runs with the library's own configuration, never flipping it in a test body.
"""

from __future__ import annotations

import json
import os
import shutil
import statistics
import tempfile
from pathlib import Path

# A new, empty cache folder for this run (fogbayes._config: JAX programs, Numba loops),
# shared by the xdist workers, the CLI subprocesses and the notebooks (they inherit the
# environment): a program compiled in one process is read by the others, as on a user's
# machine after the first run, and nothing compiled by an earlier run is used.
if "PYTEST_XDIST_WORKER" not in os.environ and "FOGBAYES_CACHE_DIR" not in os.environ:
    os.environ["FOGBAYES_CACHE_DIR"] = _RUN_CACHE = tempfile.mkdtemp(prefix="fogbayes-test-")

# xdist's workers already fill the cores: each runs its independent calls one after another
# (fogbayes.support.threads), as a user would set it for Dask workers
if int(os.environ.get("PYTEST_XDIST_WORKER_COUNT", "1")) > 1:
    os.environ.setdefault("FOGBAYES_THREADS", "1")

import fogbayes  # noqa: E402, F401  (float64 and the program cache; before JAX: _config)
import pytest  # noqa: E402
from _measured import MEASURED, SHARED, measured_path  # noqa: E402, F401  (re-exported)


def pytest_collection_modifyitems(config, items):
    """Slowest test files first (seconds from ``file_seconds.json``; refresh it with
    ``tests/file_seconds.py``).

    The README runs the suite on two workers, one file at a time each (``--dist loadfile``,
    ``--no-loadscope-reorder`` so that xdist keeps this order). Longest-first leaves short
    files for the end, so both workers finish together: by the recorded times the slower
    worker's share is 1066 s of 2133 s (1094 s in file-name order). The order inside a file is kept.
    """
    table = json.loads((Path(__file__).with_name("file_seconds.json")).read_text())["seconds"]
    unknown = statistics.median(table.values())  # a new file: a typical one
    items.sort(key=lambda item: -table.get(item.nodeid.split("::", 1)[0], unknown))


def pytest_unconfigure(config):
    """The controller removes the run's cache folder (workers have ended by then)."""
    if "_RUN_CACHE" in globals() and not hasattr(config, "workerinput"):
        shutil.rmtree(_RUN_CACHE, ignore_errors=True)


@pytest.fixture
def measured():
    """Fixture form of :func:`measured_path`."""
    return measured_path
