"""Test configuration: strict numerics and access to the measured data in ../shared.

float64 is switched on by importing fogbayes (fogbayes._config); we import it here so
every test runs with the library's own configuration, never flipping it in a test body.
"""

from __future__ import annotations

import gc
import os
from pathlib import Path

import jax
import pytest

import fogbayes  # noqa: F401  (turns on jax_enable_x64)

REPO = Path(__file__).resolve().parents[1]
SHARED = Path(os.environ.get("FOGBAYES_SHARED", REPO.parent / "shared"))
MEASURED = SHARED / "data" / "measured"


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

    Each XLA:CPU executable keeps three anonymous memory maps (code, read-only data, data)
    for as long as a jit cache holds it. The whole suite compiles ~20 000 distinct
    programs (many shapes, orders and static options) in one process, which passes
    ``vm.max_map_count``; the next ``mmap`` then fails inside LLVM and the process dies
    (SIGSEGV or SIGABRT, in whichever test compiled next: CI of the eleventh session at
    ~92 %; 65 337 maps at the abort when measured). A library process re-running the same
    shapes does not grow (four loops on new records: 3 207 -> 3 446 maps), so this is a
    test-suite measure, taken only past ``MAP_HEADROOM`` so modules keep sharing programs.
    """
    yield
    if _memory_maps() > MAP_HEADROOM:
        jax.clear_caches()
        gc.collect()


def measured_path(*parts: str) -> Path:
    """Path of a measured data file in ../shared; skip (or fail under CI) when absent.

    The ADIS16405 runs are licensed for non-commercial use only, so they are never copied
    into this repository: tests read them from ../shared/data/measured.
    """
    p = MEASURED.joinpath(*parts)
    if not p.exists():
        msg = f"measured data not found at {p} (set FOGBAYES_SHARED to the shared/ folder)"
        if os.environ.get("CI"):
            pytest.fail(msg + "; CI must have ../shared beside the clone")
        pytest.skip(msg)
    return p


@pytest.fixture
def measured():
    """Fixture form of :func:`measured_path`."""
    return measured_path
