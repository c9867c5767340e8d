"""Streams compensate on the host: a bias-t or thermal stream never starts JAX.

Chunks are read from and written to host memory, so the compiled CPU loop does the work
whatever JAX's default device. On an H200 machine XLA on the GPU took 18.2 s and 4.3 GB of
peak memory for a 2e8-sample stream (JAX's CUDA start-up alone: 4.1 GB) against the loop's
10.2 s and 0.7 GB (benchmarks/RESULTS_gpu.md). Here that shows as: the stream's process never
imports ``jax``, and its output still equals the in-memory compensation.
"""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

from fogbayes.data import save

CHILD = r"""
import json, sys
from fogbayes.stream import compensate_stream
res = compensate_stream(sys.argv[1], json.load(open(sys.argv[2])), sys.argv[3], rows=1000)
print(json.dumps({"jax": "jax" in sys.modules, "outliers": res.outliers}))
"""


@pytest.mark.parametrize("model", ["bias-t", "thermal"])
def test_a_thermal_stream_runs_without_jax(tmp_path, model):
    from fogbayes.simulate import simulate
    from fogbayes.thermal.workflow import compensate_recording, fit_recording

    rec = simulate("paper004", seed=3, soak=1200.0, ramp_rate=2.0).recording.slice(0, 6000)
    fit = json.loads(json.dumps(fit_recording(rec, model=model)))  # as the CLI reads it
    (tmp_path / "fit.json").write_text(json.dumps(fit))
    src = save(rec, tmp_path / "run.npz")
    out = subprocess.run([sys.executable, "-c", CHILD, str(src), str(tmp_path / "fit.json"),
                          str(tmp_path / "out.npz")], capture_output=True, text=True, check=True)
    child = json.loads(out.stdout.strip().splitlines()[-1])
    assert child["jax"] is False
    ref = compensate_recording(rec, fit)
    with np.load(tmp_path / "out.npz") as got:
        np.testing.assert_array_equal(got["outlier"], ref["outlier"])
        np.testing.assert_allclose(got["output"], ref["output"], rtol=0, atol=1e-12)
    assert child["outliers"] == int(ref["outlier"].sum())
