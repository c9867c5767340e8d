"""Where the measured data live (../shared beside the clone, or $FOGBAYES_SHARED).

A module of its own, not conftest.py: ``notebooks/conftest.py`` is also imported under the
name ``conftest``, so tests import these helpers from here.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
SHARED = Path(os.environ.get("FOGBAYES_SHARED", REPO.parent / "shared"))
MEASURED = SHARED / "data" / "measured"


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
