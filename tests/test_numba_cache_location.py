"""Numba's compiled-function cache goes to the user's cache folder, never into the package.

In a fresh process with ``FOGBAYES_CACHE_DIR`` pointed at an empty folder, compiling a
fogbayes loop writes its cache files there and none beside the source (the in-tree
``__pycache__`` that made ``site-packages/fogbayes`` a namespace package after
``pip install .`` then ``pip install -e .``).
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import fogbayes

PACKAGE = Path(fogbayes.__file__).resolve().parent


def _in_tree() -> set[Path]:
    return {p for p in PACKAGE.rglob("*") if p.suffix in (".nbi", ".nbc")}


def test_compiled_loops_cache_in_the_user_cache_folder(tmp_path):
    before = _in_tree()
    code = ("import numpy as np; from fogbayes.stats.allan import allan_deviation; "
            "allan_deviation(np.random.default_rng(0).normal(size=4096), 1.0)")
    env = {**os.environ, "FOGBAYES_CACHE_DIR": str(tmp_path)}
    subprocess.run([sys.executable, "-c", code], check=True, env=env, cwd=tmp_path)
    cached = list((tmp_path / "numba").rglob("*.nbi"))
    assert cached, "no cache index written under FOGBAYES_CACHE_DIR"
    assert any("allan_loops" in p.name for p in cached)
    assert _in_tree() == before  # nothing new beside the sources
