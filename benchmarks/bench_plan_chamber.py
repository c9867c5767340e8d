"""Check the chamber planner by simulation: the loop's right-first before and after.

``fogbayes.plan.programme`` predicts from the noise model and the programme alone how often
the loop's duel rejects the rival of a true effect (thermal lag vs the gradient of the two
channels, Shupe vs lag, ...). This script plans a programme for the study's configuration A
(3 h at 10 Hz, the thermal scenario's noise N 0.005, B 0.02, K 0.02, channels lagging 300 s
and 900 s, -20..60 deg C, ramps up to 5 deg C/min), then runs ``fogbayes.loop.run_loop`` on
records simulated under the generic test (before) and under the planned programme (after),
with the same seeds: a planted ``thermal_lag`` (coeff 0.01 deg/h per deg C, tau 1800 s),
``temperature_gradient``, ``temperature_rate`` (the registry defaults) and clean records.

    python benchmarks/bench_plan_chamber.py --seeds 12 --others 4 --out plan_chamber.json
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from bench_loop import _right_first, run_cases  # noqa: E402

CONFIG = dict(model="bias-t", profile="thermal", magnitude=1.0, noise="default", fs=10.0,
              duration=3 * 3600.0)
PAIRS = [("thermal_lag", "temperature_gradient", 0.01, 1800.0),
         ("thermal_lag", "temperature_rate", 0.01, 1800.0),
         ("temperature_rate", "thermal_lag", 0.3, None),
         ("temperature_rate", "temperature_gradient", 0.3, None)]


def make_plan(seed: int = 0) -> dict:
    from fogbayes.plan.programme import Pair, noise_for_plan, plan_programme

    noise, dur, fs = noise_for_plan(allan=dict(N=0.005, B=0.02, K=0.02),
                                    duration=CONFIG["duration"], fs=CONFIG["fs"], seed=seed)
    plan = plan_programme(noise, [Pair(*p) for p in PAIRS], duration=dur, fs=fs,
                          max_rate=5.0, seed=seed)
    return plan.to_json()


def main() -> None:
    import multiprocessing

    multiprocessing.set_start_method("spawn")  # the plan started JAX's threads: no fork
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=12, help="lag records per programme")
    ap.add_argument("--others", type=int, default=4,
                    help="gradient, Shupe and clean records per programme")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--out", default="plan_chamber.json")
    args = ap.parse_args()
    t0 = time.time()
    plan = make_plan()
    print(f"plan in {time.time() - t0:.1f} s: best {plan['best']['name']}")
    for key in ("baseline", "best"):
        print(key, plan[key]["name"], json.dumps(plan[key]["noncentrality"]),
              json.dumps(plan[key]["power"]))
    json.dump(plan, open(args.out.replace(".json", "_plan.json"), "w"), indent=1)
    progs = {"before": None, "after": plan["best"]["segments"]}
    todo = []  # before and after of one record side by side: a cut-short run stays paired
    for eff, n in (("thermal_lag", args.seeds), ("temperature_gradient", args.others),
                   ("temperature_rate", args.others), (None, args.others)):
        todo += [dict(CONFIG, effect=eff, seed=s, programme=prog, segments=segs)
                 for s in range(n) for prog, segs in progs.items()]
    rows = run_cases(todo, args.out, args.workers)
    print("| effect | programme | records | right first | listed alternative | nothing added |")
    print("|---|---|---|---|---|---|")
    for eff in ("thermal_lag", "temperature_gradient", "temperature_rate", None):
        for prog in progs:
            rs = [r for r in rows if r["effect"] == eff and r["programme"] == prog]
            if not rs:
                continue
            right = sum(_right_first(r) for r in rs) if eff else "-"
            alt = sum(eff in r["alternatives"] for r in rs) if eff else "-"
            clean = sum(not r["added"] for r in rs)
            print(f"| {eff} | {prog} | {len(rs)} | {right} | {alt} | {clean} |")


if __name__ == "__main__":
    main()
