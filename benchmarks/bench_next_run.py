"""Held-out calibration: the loop on run A calibrates run B of the same sensor.

Usage::

    python benchmarks/bench_next_run.py [--workers 2] [--seeds 2] [--out benchmarks/next_run.json]
    python benchmarks/bench_next_run.py --composite   # -> benchmarks/next_run_composite.json
    python benchmarks/bench_next_run.py --composite --effects scale_factor_asymmetry,scale_factor_nonlinearity

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

``--composite``: the scale factor linear in T (``scale_factor_temperature``, registry size)
on paper 000's rate table. Run A: 10 temperatures x 14 rates, 2 h at 1 Hz; run B: the same
sensor on another grid (-20..40 deg C, 6 temperatures x 8 rates within A's, 1.5 h). Base
model ``composite`` (linear scale, quadratic bias); the plain fit is ``fogbayes fit -m
composite`` (paper 000's classification fit). The error is that of the estimated input
rate W (deg/s) against the table's; the oracle's is B's noise divided by the true slope
dU/dW = 3600 (1 + k (T - T_ref)) (deg/h per deg/s).
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


def loop_then_apply(a, b, model: str, seed: int):
    """The loop on run A at the CLI's defaults, its document through JSON (what ``fogbayes
    loop --json`` writes and ``compensate --params`` reads), applied to run B.
    Returns (loop result, applied calibration, the loop's wall time on A in s)."""
    from fogbayes.loop import run_loop
    from fogbayes.loop.calibration import apply_calibration
    from fogbayes.loop.calibration_doc import validate_loop_document

    t0 = time.time()
    res = run_loop(a, model, seed=seed)
    wall = time.time() - t0
    doc = validate_loop_document(json.loads(json.dumps(res.to_json())), "loop")
    return res, apply_calibration(doc, b), wall


def run_case(case: dict) -> dict:
    import numpy as np

    from fogbayes.loop.metrics import block_rms
    from fogbayes.simulate.scenarios import simulate
    from fogbayes.thermal import workflow as thermal

    law, s = _law(case["effect"]), case["seed"]
    a = simulate("thermal", seed=s, fs=1.0, duration=3 * 3600.0, effects=law,
                 temperature_noise=0.01).recording
    sim_b = simulate("thermal", seed=s + 1000, fs=1.0, duration=2.5 * 3600.0, effects=law,
                     temperature_noise=0.01, **RUN_B)
    b = sim_b.recording
    res, applied, wall = loop_then_apply(a, b, "bias-t", s)
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


GRID_B = {"temperatures": (-20.0, -10.0, 0.0, 10.0, 20.0, 40.0),
          "rates": (2.0, -2.0, 10.0, -10.0, 40.0, -40.0, 80.0, -80.0)}


def _true_slope(eff: str, p: dict, w, T):
    """dU/dW of the simulated sensor (deg/h per deg/s): the table's 3600 plus the planted
    scale-factor effect's derivative (central difference of its closed form in
    fogbayes.simulate.effects; |W| at W = 0 counts as 0)."""
    import inspect

    from fogbayes.simulate import effects as fx

    f = getattr(fx, eff)
    kw = {k: v for k, v in p.items() if k in inspect.signature(f).parameters}
    if "T" in inspect.signature(f).parameters:
        kw["T"] = T
    h = 1e-3
    return 3600.0 + (f(w + h, **kw) - f(w - h, **kw)) / (2 * h)


def run_composite_case(case: dict) -> dict:
    import numpy as np

    from fogbayes.loop.metrics import block_rms
    from fogbayes.loop.testbed import _scaled
    from fogbayes.simulate.scenarios import simulate
    from fogbayes.composite import workflow as composite

    eff = case["effect"]
    law = {eff: _scaled(eff, 1.0, None)}
    s = case["seed"]
    a = simulate("ratetable", seed=s, fs=1.0, duration=2 * 3600.0, effects=law).recording
    sim_b = simulate("ratetable", seed=s + 1000, fs=1.0, duration=1.5 * 3600.0, effects=law,
                     **GRID_B)
    b = sim_b.recording
    res, applied, wall = loop_then_apply(a, b, "composite", s)
    flag = applied.columns["outlier"]
    w_true = np.asarray(b.input_rate, float)
    p = sim_b.truth.params["effects"][eff]
    T = np.asarray(b.temperatures)[:, 0]  # the table's soaked temperature (no sensor noise)
    slope = _true_slope(eff, p, w_true, T)
    noise = np.sum(list(sim_b.truth.noise_parts.values()), axis=0)
    fit_doc = composite.fit_recording(a, model="composite")
    by_fit = np.asarray(composite.compensate_recording(b, fit_doc)["rate"], float)

    def rms(err):
        ok = np.isfinite(err)
        return block_rms(b.time[ok], err[ok], flag[ok])

    row = dict(case, added=res.effects, before=rms(b.rate("deg/h") / 3600.0 - w_true),
               loop=rms(applied.columns["rate"] - w_true), fit=rms(by_fit - w_true),
               oracle=rms(noise / slope), loop_wall_s=wall,
               outside=[o["covariate"] for o in applied.outside],
               unit="deg/s (error of the estimated input rate)")
    row["loop_over_oracle"] = row["loop"] / row["oracle"]
    row["fit_over_oracle"] = row["fit"] / row["oracle"]
    return row


def summarise(rows: list[dict]) -> str:
    lines = ["| effect | seed | loop added | before | loop | plain fit | oracle | loop/oracle "
             "| fit/oracle | loop wall (s) |", "|---" * 10 + "|"]
    for r in rows:
        lines.append(f"| {r['effect'] or 'clean'} | {r['seed']} | {', '.join(r['added']) or '-'} "
                     f"| {r['before']:.4g} | {r['loop']:.4g} | {r['fit']:.4g} | {r['oracle']:.4g}"
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
    ap.add_argument("--out", default=None)
    ap.add_argument("--composite", action="store_true",
                    help="the rate-table case (scale factor in T) instead of the thermal ones")
    ap.add_argument("--effects", default="scale_factor_temperature",
                    help="--composite: comma-separated scale-factor effects (also "
                         "scale_factor_asymmetry, scale_factor_nonlinearity)")
    args = ap.parse_args()
    if args.composite:
        todo = [dict(effect=e, seed=s) for e in args.effects.split(",")
                for s in range(args.seeds)]
        fn, out = run_composite_case, args.out or DEFAULT_OUT.replace(".json", "_composite.json")
    else:
        todo = [dict(effect=e, seed=s) for s in range(args.seeds) for e in EFFECTS]
        fn, out = run_case, args.out or DEFAULT_OUT
    args.out = out
    rows = []
    with ProcessPoolExecutor(args.workers) as pool:
        for r in pool.map(fn, todo):
            rows.append(r)
            json.dump(rows, open(args.out, "w"), indent=1, default=float)
            print(r["effect"], r["seed"], r["added"], f"{r['loop_over_oracle']:.3f}",
                  f"{r['fit_over_oracle']:.3f}", f"{r['loop_wall_s']:.0f}s", flush=True)
    print(summarise(rows))


if __name__ == "__main__":
    main()
