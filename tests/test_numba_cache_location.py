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


_GENERATED = """
import numpy as np
from fogbayes.models.polynomial import PolyBasis
from fogbayes.thermal import compensate_loops as cl
rng = np.random.default_rng(0)
z = rng.normal(size=(1000, 2)); y = rng.normal(size=1000); coef = rng.normal(size=4)
basis = PolyBasis(("T", "dT/dt"), ((0, 0), (1, 0), (0, 1), (2, 1)), (0.1, -0.2), (2.0, 3.0))
out = cl.compensate_into(basis, coef, z, y, method="loop")
assert np.allclose(out, cl.compensate_numpy(basis, coef, z, y), rtol=0, atol=1e-12)
stats = cl._compiled(basis.terms).stats
print(sum(stats.cache_hits.values()), sum(stats.cache_misses.values()))
"""


def test_a_loop_compiled_from_generated_source_is_loaded_by_the_next_process(tmp_path):
    """Generated loops (thermal and composite compensation) are compiled once per machine:
    the source goes to a file in the cache folder, so Numba's disk cache serves the next
    process (a cache hit, no miss) instead of compiling again."""
    before = _in_tree()
    env = {**os.environ, "FOGBAYES_CACHE_DIR": str(tmp_path)}
    runs = [subprocess.run([sys.executable, "-c", _GENERATED], check=True, env=env,
                           cwd=tmp_path, capture_output=True, text=True).stdout.split()
            for _ in range(2)]
    assert runs[0] == ["0", "1"]  # the first process compiles (one miss) ...
    assert runs[1] == ["1", "0"]  # ... the second loads it (one hit)
    assert list((tmp_path / "numba" / "numba_src").glob("loop_*.py"))
    assert _in_tree() == before
