"""Test configuration: strict numerics and access to the measured data in ../shared.

float64 is switched on by importing fogbayes (fogbayes._config); we import it here so
every test runs with the library's own configuration, never flipping it in a test body.
"""

from __future__ import annotations

import gc
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

import fogbayes  # noqa: E402, F401  (float64 and the program cache; before JAX: _config)
import jax  # noqa: E402
import pytest  # noqa: E402
from _measured import MEASURED, SHARED, measured_path  # noqa: E402, F401  (re-exported)

#: Clear JAX's caches once a process holds this many memory maps: half the kernel's
#: default ``vm.max_map_count`` (65 530), so one module's compilations cannot reach it.
MAP_HEADROOM = 30_000


def _memory_maps() -> int:
    try:
        with open("/proc/self/maps") as f:
            return sum(1 for _ in f)
    except OSError:  # not Linux: no such limit to guard
        return 0


@pytest.fixture(autouse=True, scope="module")
def _release_compiled_code():
    """Drop JAX's compiled executables when the process nears the kernel's map limit.

    XLA:CPU (jax 0.9) compiles each kernel of a program into its own object and keeps three
    anonymous memory maps per kernel (code, read-only data, data) for as long as a jit cache
    holds the program: a small program costs ~6 maps, but one ``fit_arma`` (L-BFGS with
    its line search, and the Hessian) has ~420 kernels and costs ~1 100-1 450 maps per
    shape and order (2026-11-29). Run in one process, the ARMA test files alone add
    ~22 000 maps and the loop's ~6 300 (tests/test_loop_effects.py); the suite passes
    ``vm.max_map_count``; the next ``mmap`` then fails inside LLVM and the process dies
    (SIGSEGV or SIGABRT, in whichever test compiled next: CI of 2026-11-23 (befceaa) at
    ~92 %; 65 337 maps at the abort when measured). A library process re-running the same
    shapes does not grow (four loops on new records: 3 207 -> 3 446 maps), so this is a
    test-suite measure, taken only past ``MAP_HEADROOM`` so modules keep sharing programs.
    Since the ARMA fits and filters compile once per length bucket (2026-12-01) the ARMA
    files in one process peak at 28 936 maps (32 064 before, with four tests fewer): their
    maps are one program per order and sampler, which buckets cannot share, so the guard
    stays.
    """
    yield
    if _memory_maps() > MAP_HEADROOM:
        jax.clear_caches()
        gc.collect()


def pytest_collection_modifyitems(config, items):
    """Slowest test files first (seconds from ``file_seconds.json``; refresh it with
    ``tests/file_seconds.py``).

    The README runs the suite on two workers, one file at a time each (``--dist loadfile``,
    ``--no-loadscope-reorder`` so that xdist keeps this order). Longest-first leaves short
    files for the end, so both workers finish together: by the recorded times the slower
    worker's share drops from 1300 s to 1241 s (of 2483 s). The order inside a file is kept.
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
