"""A simulated fleet pooled by ``fogbayes pool`` once per test run, read by the files that
check that pool: tests/test_pool.py its document, tests/test_report_browser.py its report.

Eight units (10 Hz, 2^13 samples, a tactical FOG's five Allan terms, each unit's N and K
drawn about the fleet's), unit2 with four times the others' N, pooled with ``--terms N,B``
and ``--report``. Under xdist the pool is written once into the run's shared temporary
folder (the workers' base folders' parent), a file lock letting one worker pool while the
other waits; a run without workers pools into its own temporary folder.
"""

from __future__ import annotations

import fcntl
import os
import shutil
from pathlib import Path

import numpy as np

#: the fleet's sensor ids are unit0 .. unit7; this one has four times the others' N
OUTLIER = 2
N_TYPICAL = 0.01  # deg/sqrt(h), the fleet's N (each unit within ~10 % of it)


def write_units(folder: Path, n_units: int, *, n=2**14, fs=10.0, outlier=None) -> None:
    """``n_units`` recordings ``unit<u>.npz`` (sensor ids ``unit<u>``) into a new ``folder``."""
    from fogbayes import Recording, save
    from fogbayes.data import Metadata
    from fogbayes.simulate.noise import allan_noise

    rng = np.random.default_rng(11)
    folder.mkdir()
    for u in range(n_units):
        k = 0.66 * np.exp(0.2 * rng.standard_normal())
        N = N_TYPICAL * np.exp(0.1 * rng.standard_normal())
        if u == outlier:
            N *= 4.0
        y = allan_noise(4 * n, fs, seed=u, flicker_span=1, Q=0.19, N=N, B=0.165, K=k)[:n]
        save(Recording(time=np.arange(n) / fs, output=y, unit="deg/h",
                       meta=Metadata(sensor_id=f"unit{u}", sample_rate=fs)),
             folder / f"unit{u}.npz")


def pooled_fleet(tmp_path_factory) -> Path:
    """The folder holding ``runs/`` (the eight recordings), ``pool.json`` and ``pool.html``."""
    from fogbayes.cli import main

    base = tmp_path_factory.getbasetemp()
    root = (base.parent if "PYTEST_XDIST_WORKER" in os.environ else base) / "pool_fleet"
    root.mkdir(exist_ok=True)
    with open(root.parent / "pool_fleet.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)  # released when the file closes
        if not (root / "done").exists():
            for p in root.iterdir():  # what a worker that failed left behind
                shutil.rmtree(p) if p.is_dir() else p.unlink()
            write_units(root / "runs", 8, n=2**13, outlier=OUTLIER)
            assert main(["--quiet", "pool", str(root / "runs"), "--terms", "N,B",
                         "--json", str(root / "pool.json"),
                         "--report", str(root / "pool.html")]) == 0
            (root / "done").touch()
    return root
