"""A loop calibration applied to a large record, as a user runs it: ``fogbayes compensate
REC -p loop.json`` in a fresh process, in memory and with ``--stream``.

    python benchmarks/bench_stream_loop.py [--sizes 2e6 2e7] [--rows 1048576] [--json F]

For each size: a 100 Hz chamber record (output, two temperature channels, time; a ``.npz``)
and a loop document whose terms need every whole-record computation (spike medians, block
grid, Savitzky-Golay dT/dt with corners, first-order lag, play operator, warm-up). Timed
end to end, each in its own process (import, compilation and file I/O counted), with peak
RSS (VmHWM):

* ``stream``: ``compensate --stream`` to a folder of ``.npy`` (bounded memory);
* ``memory``: ``compensate`` to a CSV (the in-memory path, the whole record at once);
* ``copy``: the reference, a fresh process that reads the same columns and writes them back
  as ``.npy`` (what moving the data costs at all).

The two outputs are compared (largest difference of the compensated column, flags equal).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests"))

COPY = """
import sys, numpy as np
z = np.load(sys.argv[1])
for k in ("time", "output", "T_case", "T_fibre"):
    np.save(f"{sys.argv[2]}/{k}.npy", z[k])
"""


def make_record(path: Path, n: int) -> None:
    from fogbayes.data import Recording, save

    rng = np.random.default_rng(0)
    fs = 100.0
    t = np.arange(n) / fs
    span = t[-1]
    prog = np.interp(t, np.array([0, .1, .35, .5, .75, 1.0]) * span, [20, 20, 60, 60, -10, -10])
    T1 = prog + 0.01 * rng.standard_normal(n)  # a lag is in the model, not needed here
    T2 = T1 + 0.3 * np.sin(2 * np.pi * t / (span / 3))
    y = 0.5 + 0.01 * (T1 - 20) + 0.05 * rng.standard_normal(n)
    save(Recording(time=t, output=y, temperatures=np.column_stack([T1, T2]),
                   temperature_names=("T_case", "T_fibre")), path)


def loop_doc(span: float) -> dict:
    from test_stream_loop import _doc

    doc = _doc("bias")
    doc["calibration"]["valid"] = {}
    for tm in doc["calibration"]["terms"]:
        if tm["kind"] == "drift_exp":
            tm["params"]["tau"] = span / 20
    return doc


def timed(cmd: list[str]) -> dict:
    """Wall time and peak RSS of a fresh process (GNU time's %M)."""
    t0 = time.perf_counter()
    p = subprocess.run(["/usr/bin/time", "-f", "%M", *cmd], capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if p.returncode:
        raise RuntimeError(p.stderr[-2000:])
    rss_kb = int(p.stderr.strip().splitlines()[-1])
    return {"s": round(wall, 2), "peak_rss_mb": round(rss_kb / 1024, 1)}


def one(n: int, rows: int, work: Path) -> dict:
    rec = work / "rec.npz"
    make_record(rec, n)
    doc = work / "loop.json"
    doc.write_text(json.dumps(loop_doc(n / 100.0)))
    exe = [sys.executable, "-m", "fogbayes", "-q", "compensate", str(rec), "-p", str(doc)]
    (work / "copy").mkdir()
    out = {"n": n, "input_mb": round(rec.stat().st_size / 2**20, 1)}
    out["copy"] = timed([sys.executable, "-c", COPY, str(rec), str(work / "copy")])
    out["stream"] = timed(exe + ["-o", str(work / "s"), "--stream", "--chunk-rows", str(rows)])
    out["memory"] = timed(exe + ["-o", str(work / "m.csv")])
    import pandas as pd

    m = pd.read_csv(work / "m.csv")
    s_out, s_flag = np.load(work / "s" / "output.npy"), np.load(work / "s" / "outlier.npy")
    out["max_abs_diff_deg_h"] = float(np.max(np.abs(s_out - m["output"].to_numpy())))
    out["flags_equal"] = bool(np.array_equal(s_flag, m["outlier"].to_numpy(bool)))
    for k in ("stream", "memory"):
        out[k]["x_copy"] = round(out[k]["s"] / out["copy"]["s"], 2)
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", nargs="+", default=["2e6", "2e7"])
    ap.add_argument("--rows", type=int, default=1 << 20)
    ap.add_argument("--json", default=None)
    args = ap.parse_args()
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT,
                            capture_output=True, text=True).stdout.strip()
    res = {"date": time.strftime("%Y-%m-%d"), "commit": commit, "cpus": os.cpu_count(),
           "machine": platform.processor() or platform.machine(), "rows": args.rows, "runs": []}
    for size in args.sizes:
        with tempfile.TemporaryDirectory() as d:
            r = one(int(float(size)), args.rows, Path(d))
        print(json.dumps(r), flush=True)
        res["runs"].append(r)
    if args.json:
        Path(args.json).write_text(json.dumps(res, indent=1))


if __name__ == "__main__":
    main()
