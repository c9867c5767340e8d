"""Held-out calibration: the loop on run A calibrates run B of the same sensor.

Usage::

    python benchmarks/bench_next_run.py [--workers 2] [--seeds 2] [--out benchmarks/next_run.json]

For each undeclared effect (registry default size) on top of the declared quadratic bias in
T, and for clean sensors:

* run A: the generic chamber test, 3 h at 1 Hz, -20..60 deg C about 20 (seed s);
* run B: the same sensor (same bias law and effect, new noise: seed s + 1000) on another
  programme: 2.5 h, -10..50 deg C about 25 (other ramp rates and soak levels);
* ``run_loop(A, "bias-t")`` (the CLI's defaults: 5 steps, alpha 0.01), its document through
  JSON, applied to B by :func:`fogbayes.loop.calibration.apply_calibration` (what
  ``fogbayes compensate B --params loop.json`` does);
* the baseline: ``fogbayes fit -m bias-t`` on A (its default order 3, no dT/dt), applied to B;
* the judge: B's truth. ``oracle`` = 10 s RMS of B's rate minus its true bias (noise only).

Rows: effect, seed, what the loop added, 10 s RMS of B before / with the loop's calibration /
with the plain fit / oracle (deg/h), the ratios to the oracle, and the loop's wall time on A.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))

EFFECTS = (None, "temperature_rate", "temperature_gradient", "thermal_lag",
           "thermal_hysteresis", "temperature_order")
QUADRATIC = {"coeffs": [0.5, 0.01, 2e-4], "T_ref": 20.0}
RUN_B = {"low": -10.0, "high": 50.0, "room": 25.0}
DEFAULT_OUT = os.path.join(HERE, "next_run.json")


def _law(effect: str | None) -> dict:
    from fogbayes.loop.testbed import _scaled

    law = {"temperature_order": dict(QUADRATIC)}
    if effect is not None:
        law[effect] = _scaled(effect, 1.0, None)  # temperature_order: quadratic + cubic
    return law


def run_case(case: dict) -> dict:
    import numpy as np

    from fogbayes.loop import run_loop
    from fogbayes.loop.calibration import apply_calibration
    from fogbayes.loop.calibration_doc import validate_loop_document
    from fogbayes.loop.metrics import block_rms
    from fogbayes.simulate.scenarios import simulate
    from fogbayes.workflow import thermal

    law, s = _law(case["effect"]), case["seed"]
    a = simulate("thermal", seed=s, fs=1.0, duration=3 * 3600.0, effects=law,
                 temperature_noise=0.01).recording
    sim_b = simulate("thermal", seed=s + 1000, fs=1.0, duration=2.5 * 3600.0, effects=law,
                     temperature_noise=0.01, **RUN_B)
    b = sim_b.recording
    t0 = time.time()
    res = run_loop(a, "bias-t", seed=s)
    wall = time.time() - t0
    doc = validate_loop_document(json.loads(json.dumps(res.to_json())), "loop")
    applied = apply_calibration(doc, b)
    flag = applied.columns["outlier"]
    rate = b.rate("deg/h")
    truth = np.sum(list(sim_b.truth.effects.values()), axis=0)
    fit_doc = thermal.fit_recording(a, model="bias-t")
    by_fit = thermal.compensate_recording(b, fit_doc)["output"]  # deg/h: B's unit

    def rms(x):
        return block_rms(b.time, x, flag)

    row = dict(case, added=res.effects, before=rms(rate), loop=rms(rate - applied.bias_deg_h),
               fit=rms(by_fit), oracle=rms(rate - truth), loop_wall_s=wall,
               outside=[o["covariate"] for o in applied.outside])
    row["loop_over_oracle"] = row["loop"] / row["oracle"]
    row["fit_over_oracle"] = row["fit"] / row["oracle"]
    return row


def summarise(rows: list[dict]) -> str:
    lines = ["| effect | seed | loop added | before | loop | plain fit | oracle | loop/oracle "
             "| fit/oracle | loop wall (s) |", "|---" * 10 + "|"]
    for r in rows:
        lines.append(f"| {r['effect'] or 'clean'} | {r['seed']} | {', '.join(r['added']) or '-'} "
                     f"| {r['before']:.3f} | {r['loop']:.4f} | {r['fit']:.4f} | {r['oracle']:.4f}"
                     f" | {r['loop_over_oracle']:.3f} | {r['fit_over_oracle']:.3f} "
                     f"| {r['loop_wall_s']:.0f} |")
    ok = sum(r["loop_over_oracle"] <= 1.2 for r in rows)
    better = sum(r["loop"] < r["fit"] for r in rows if r["effect"] is not None)
    n_eff = sum(r["effect"] is not None for r in rows)
    lines.append(f"\nloop within 1.2x the oracle on run B: {ok}/{len(rows)}; loop better than "
                 f"the plain fit: {better}/{n_eff} records with an effect")
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--seeds", type=int, default=2)
    ap.add_argument("--out", default=DEFAULT_OUT)
    args = ap.parse_args()
    todo = [dict(effect=e, seed=s) for s in range(args.seeds) for e in EFFECTS]
    rows = []
    with ProcessPoolExecutor(args.workers) as pool:
        for r in pool.map(run_case, todo):
            rows.append(r)
            json.dump(rows, open(args.out, "w"), indent=1, default=float)
            print(r["effect"], r["seed"], r["added"], f"{r['loop_over_oracle']:.3f}",
                  f"{r['fit_over_oracle']:.3f}", f"{r['loop_wall_s']:.0f}s", flush=True)
    print(summarise(rows))


if __name__ == "__main__":
    main()
