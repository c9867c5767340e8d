"""Closed-loop study and timing: does the loop add the right effect first, and nothing on clean data?

Usage::

    python benchmarks/bench_loop.py study [--quick] [--workers 2] [--out benchmarks/loop_study.json]
    python benchmarks/bench_loop.py timing           # 6 h, 10 Hz record through `fogbayes loop`
    python benchmarks/bench_loop.py measured         # ADIS16405 (allan) and PAN TVAC (bias-t)

Study design (every case a fresh simulated recording, fixed seeds):
  * every effect name, present but undeclared, on its base model (thermal effects on
    ``bias-t`` over the generic heating/cooling test; scale-factor effects on ``composite``
    over paper 000's rate table; ``markov_noise`` on ``bias-t`` and ``allan``);
  * magnitudes 1x and 2x the simulator's registry default, noise mixes fog / flicker / walk
    / white (:data:`fogbayes.loop.testbed.NOISE_MIXES`), sample rates 1, 2, 10 Hz, durations
    3 h and 6 h, the generic thermal test and paper 004's programme, several seeds;
  * clean recordings (no extra effect) over the same grid.
Per case: the first added effect; the final 10 s-block RMS against the oracle's (the true
model -- base terms plus the planted effect at its true parameters -- fitted the same way);
the run time. ``RESULTS_loop.md`` holds the table.
"""

from __future__ import annotations

import argparse
import itertools
import json
import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor

import numpy as np

# Run against the checkout this script lives in, whatever `pip install -e` points at.
REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, REPO)
os.environ["PYTHONPATH"] = REPO + os.pathsep + os.environ.get("PYTHONPATH", "")

THERMAL = ("temperature_order", "temperature_rate", "temperature_gradient", "thermal_hysteresis",
           "thermal_lag", "time_drift", "periodic", "step", "markov_noise")
RATE_TABLE = ("scale_factor_nonlinearity", "scale_factor_asymmetry", "scale_factor_temperature")


def run_case(case: dict) -> dict:
    import fogbayes  # noqa: F401
    from fogbayes.diagnose.fitting import fit_terms
    from fogbayes.loop import run_loop
    from fogbayes.loop.bases import base_terms
    from fogbayes.loop.metrics import block_rms
    from fogbayes.loop.testbed import make_record, oracle_terms

    tr = make_record(case["effect"], seed=case["seed"], duration=case["duration"], fs=case["fs"],
                     magnitude=case["magnitude"], noise=case["noise"], profile=case["profile"])
    t0 = time.time()
    res = run_loop(tr.recording, case["model"], max_steps=case.get("max_steps", 3), seed=case["seed"])
    wall = time.time() - t0
    out = dict(case, added=res.effects, rms_initial=res.initial.rms, rms_final=res.final.rms,
               wall_s=wall, stop=res.stop.reason)
    if case["effect"] is not None:
        ctx = res.context
        base = base_terms(ctx, case["model"])
        ofit = fit_terms(ctx, oracle_terms(ctx, base, case["effect"], tr.effect_params))
        out["rms_oracle"] = block_rms(ctx.cov.t, ofit.residual, ctx.outlier)
    return out


def cases(quick: bool) -> list[dict]:
    seeds = (0, 1) if quick else (0, 1, 2)
    grid = []
    for eff in THERMAL + (None,):
        for mag, noise, fs, dur, prof in [(1.0, "default", 10.0, 3 * 3600, "thermal"),
                                          (2.0, "flicker", 1.0, 6 * 3600, "thermal"),
                                          (1.0, "walk", 10.0, 6 * 3600, "paper004"),
                                          (2.0, "white", 2.0, 3 * 3600, "thermal")]:
            if quick and noise in ("walk", "white"):
                continue
            for sd in seeds:
                grid.append(dict(effect=eff, model="bias-t", profile=prof, magnitude=mag,
                                 noise=noise, fs=fs, duration=float(dur), seed=sd))
    for eff in RATE_TABLE + (None,):
        for mag, noise, fs in [(1.0, "default", 10.0), (0.1, "flicker", 2.0)]:
            for sd in seeds:
                grid.append(dict(effect=eff, model="composite", profile="ratetable",
                                 magnitude=mag, noise=noise, fs=fs, duration=2 * 3600.0, seed=sd))
    return grid


def summarise(rows: list[dict]) -> str:
    lines = ["| effect | base | cases | right first | nothing added "
             "| final/oracle RMS (median, max) | within 10 % |",
             "|---|---|---|---|---|---|---|"]
    key = lambda r: (str(r["effect"]), r["model"])  # noqa: E731
    for (eff, model), grp in itertools.groupby(sorted(rows, key=key), key=key):
        g = list(grp)
        if eff == "None":
            clean = sum(1 for r in g if not r["added"])
            lines.append(f"| (clean) | {model} | {len(g)} | - | {clean}/{len(g)} | - | - |")
            continue
        right = sum(1 for r in g if r["added"][:1] == [eff])
        ratio = np.array([r["rms_final"] / r["rms_oracle"] for r in g])
        lines.append(f"| {eff} | {model} | {len(g)} | {right}/{len(g)} | - | "
                     f"{np.median(ratio):.3f}, {ratio.max():.3f} | {int(np.sum(ratio <= 1.1))}/{len(g)} |")
    return "\n".join(lines)


def study(args) -> None:
    todo = cases(args.quick)
    done = []
    if os.path.exists(args.out):
        done = json.load(open(args.out))
    seen = {json.dumps({k: r[k] for k in todo[0]}, sort_keys=True) for r in done}
    todo = [c for c in todo if json.dumps(c, sort_keys=True) not in seen]
    print(f"{len(todo)} cases to run ({len(done)} already done)", flush=True)
    with ProcessPoolExecutor(args.workers) as pool:
        for r in pool.map(run_case, todo):
            done.append(r)
            json.dump(done, open(args.out, "w"), indent=1, default=float)
            print(r["effect"], r["model"], r["noise"], r["fs"], r["seed"], "->", r["added"],
                  f"{r['wall_s']:.1f}s", flush=True)
    print(summarise(done))


def timing(args) -> None:
    """Wall time of `fogbayes loop` (a fresh process: compile included) on a 6 h 10 Hz record."""
    import subprocess
    import tempfile

    import fogbayes  # noqa: F401
    from fogbayes.data import save
    from fogbayes.loop.testbed import make_record

    tmp = tempfile.mkdtemp()
    rec = make_record("thermal_lag", seed=5, duration=6 * 3600.0, fs=10.0).recording
    path = os.path.join(tmp, "six_hours.csv")
    save(rec, path)
    t_copy = time.time()
    np.copy(rec.output)
    t_copy = time.time() - t_copy
    cmd = [sys.executable, "-c", "import sys, fogbayes.cli as c, fogbayes.cli.loop; "
           "sys.exit(c.main(sys.argv[1:]))", "loop", path, "--model", "bias-t",
           "--json", os.path.join(tmp, "loop.json"), "--compensated", os.path.join(tmp, "comp.csv")]
    t0 = time.time()
    subprocess.run(cmd, check=True, cwd=REPO)
    wall = time.time() - t0
    doc = json.load(open(os.path.join(tmp, "loop.json")))
    print(f"n = {rec.n} samples; fogbayes loop wall time {wall:.1f} s (fresh process, "
          f"JIT compile included); effects {[s['effect'] for s in doc['steps']]}; "
          f"memory copy of the output {t_copy * 1e3:.2f} ms; cores {os.cpu_count()}")


def measured(args) -> None:
    import fogbayes  # noqa: F401
    from fogbayes.data import Metadata, Recording
    from fogbayes.loop import run_loop
    from fogbayes.workflow.pan_tvac import load_pan_tvac

    shared = os.environ.get("FOGBAYES_SHARED", os.path.join(os.path.dirname(__file__), "..", "..", "shared"))
    d = np.load(os.path.join(shared, "data/measured/adis16405_static_ucalgary/adis_16405_imu1.npz"))
    for j, name in enumerate(("gyro x", "gyro y", "gyro z")):
        x = d["data"][:, j]
        rec = Recording(time=np.arange(x.size) / 100.0, output=x, unit="deg/s",
                        meta=Metadata(sensor_id="adis16405-imu1", sample_rate=100.0))
        res = run_loop(rec, "allan", max_steps=3, seed=0)
        print("ADIS16405 imu1", name, json.dumps(res.to_json(), default=float)[:2000])
    pan = os.path.join(shared, "data/measured/pan_lsm6dsm_tvac_cold/TVCtest3_7_20.csv")
    for ax in "xyz":
        res = run_loop(load_pan_tvac(pan, ax), "bias-t", max_steps=3, seed=0)
        print("PAN TVAC", ax, json.dumps(res.to_json(), default=float)[:2000])


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("what", choices=("study", "timing", "measured"))
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--out", default=os.path.join(os.path.dirname(__file__), "loop_study.json"))
    args = ap.parse_args()
    {"study": study, "timing": timing, "measured": measured}[args.what](args)


if __name__ == "__main__":
    main()
