"""``fogbayes fit REC -m bias-t`` is least squares on NumPy: a fresh process that runs it on a
1 h record must not import JAX, NumPyro, Numba, scipy.linalg or pandas (their import, and
loading Numba's cached loops, are most of the command's wall time; the CSV's numbers are
parsed by NumPy), and its document is the library's ``fit_recording`` on the file as pandas
reads it (same coefficients, bit for bit)."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np

import fogbayes
from fogbayes.simulate import simulate
from fogbayes.thermal.workflow import fit_recording

_CODE = """
import json, sys
from fogbayes.cli import main
heavy = ("jax", "numpyro", "numba", "scipy.linalg", "pandas")
after_import = sorted(m for m in heavy if m in sys.modules)
rc = main(["-q", "fit", sys.argv[1], "-m", "bias-t", "--json", sys.argv[2]])
print(json.dumps({"rc": rc, "after_import": after_import,
                  "after_fit": sorted(m for m in heavy if m in sys.modules)}))
"""


def test_fit_bias_t_in_a_fresh_process_imports_no_jax(tmp_path):
    rec = simulate("thermal", seed=2, duration=3600.0, fs=1.0).recording
    src = fogbayes.save(rec, tmp_path / "rec.csv")
    out = tmp_path / "fit.json"
    run = subprocess.run([sys.executable, "-c", _CODE, str(src), str(out)], capture_output=True,
                         text=True, check=True)
    seen = json.loads(run.stdout.strip().splitlines()[-1])
    assert seen == {"rc": 0, "after_import": [], "after_fit": []}
    doc = json.loads(out.read_text())
    assert "pandas" in sys.modules  # save() wrote with it: load() here reads with it
    ref = fit_recording(fogbayes.load(src), model="bias-t")
    np.testing.assert_array_equal(doc["params"]["coef"], ref["params"]["coef"])


def test_fit_without_json_prints_the_result_and_writes_nothing(tmp_path):
    """``--json`` is optional: the summary is printed, no file is written, and the user is told
    how to keep the calibration (before, click stopped with "Missing option '--json'")."""
    rec = simulate("thermal", seed=2, duration=3600.0, fs=1.0).recording
    src = fogbayes.save(rec, tmp_path / "rec.csv")
    run = subprocess.run([sys.executable, "-m", "fogbayes", "fit", str(src), "-m", "bias-t"],
                         capture_output=True, text=True, cwd=tmp_path)
    assert run.returncode == 0, run.stderr
    assert "bias-t: converged=True" in run.stderr
    assert "add --json" in run.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["rec.csv"]
