"""The closed loop on records outside the study's grid: held-out set-ups and the CLI's defaults.

Usage::

    python benchmarks/bench_loop_holdout.py setups   [--workers 2] [--out benchmarks/loop_holdout.json]
    python benchmarks/bench_loop_holdout.py defaults [--workers 2] [--out benchmarks/loop_defaults.json]
    python benchmarks/bench_loop_holdout.py thermal-base [--workers 2] [--out benchmarks/loop_thermal_base.json]

``setups``: every thermal effect on two set-ups the study and the sweep never used (paper
004's programme with the "fog" noise mix at 2 Hz for 6 h; the generic chamber test at
5 Hz for 4 h with every effect at 1.5x its registry size), seeds 300-301, plus 4 clean
records each (seeds 300-303). Nothing in the method was changed after these ran.

``defaults``: what a user gets from ``fogbayes simulate thermal --effect NAME`` (the 6.3 h,
10 Hz chamber test, the scenario's own noise, every effect at its registry default, no
temperature noise) through ``fogbayes loop --model bias-t``: seeds 0-2, 6 clean records.
Rows carry the oracle's 10 s-block RMS (the true model fitted as the loop fits its own).

``thermal-base``: the ``thermal`` base model (paper 004's eq. 14: quadratic in T and in
dT/dt) on what ``fogbayes simulate paper004 --effect NAME`` writes (paper 004's programme,
1 Hz, its own Shupe term 4 deg/h per deg C/min declared by the base), every effect the
base lacks at its registry default: seeds 0-1, 6 clean records.
"""

from __future__ import annotations

import argparse
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import bench_loop as bl  # (also puts this checkout first on sys.path)

#: magnitude, noise mix, fs (Hz), duration (s), profile -- none of them in bench_loop's grids
SETUPS = [(1.0, "fog", 2.0, 6 * 3600.0, "paper004"), (1.5, "fog", 5.0, 4 * 3600.0, "thermal")]


def setup_cases() -> list[dict]:
    grid = []
    for eff in bl.THERMAL + (None,):
        for mag, noise, fs, dur, prof in SETUPS:
            for sd in ((300, 301) if eff else (300, 301, 302, 303)):
                grid.append(dict(effect=eff, model="bias-t", profile=prof, magnitude=mag,
                                 noise=noise, fs=fs, duration=dur, seed=sd))
    return grid


#: scenario each base model is run on (``defaults``: bias-t; ``thermal-base``: thermal)
SCENARIO = {"bias-t": "thermal", "thermal": "paper004"}


def default_case(case: dict) -> dict:
    """One `simulate SCENARIO --effect NAME` record through the loop, with the oracle's RMS."""
    import fogbayes  # noqa: F401
    from fogbayes.loop import run_loop
    from fogbayes.simulate.scenarios import simulate

    eff, model = case["effect"], case["model"]
    sim = simulate(SCENARIO[model], seed=case["seed"], effects={eff: {}} if eff else None)
    t0 = time.time()
    res = run_loop(sim.recording, model, max_steps=3, seed=case["seed"])
    out = bl.loop_row(case, res, time.time() - t0)
    if eff is not None:
        params = dict(sim.truth.params["effects"][eff])
        if eff == "temperature_order":  # the planted part: the cubic on top of the quadratic
            params = {"coeffs": [0.0, 0.0, 0.0, params["coeffs"][3]], "T_ref": params["T_ref"]}
        out["rms_oracle"] = bl.oracle_rms(res, model, eff, params)
    return out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("what", choices=("setups", "defaults", "thermal-base"))
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--out", default=None)
    args = ap.parse_args()
    name = {"setups": "holdout", "defaults": "defaults", "thermal-base": "thermal_base"}[args.what]
    out = args.out or os.path.join(HERE, f"loop_{name}.json")
    if args.what == "setups":
        rows = bl.run_cases(setup_cases(), out, args.workers)
    elif args.what == "defaults":
        rows = bl.run_cases([dict(effect=eff, model="bias-t", seed=sd)
                             for eff in bl.THERMAL + (None,)
                             for sd in (range(3) if eff else range(6))], out, args.workers,
                            fn=default_case)
    else:
        rows = bl.run_cases([dict(effect=eff, model="thermal", seed=sd)
                             for eff in bl.THERMAL + (None,) if eff != "temperature_rate"
                             for sd in (range(2) if eff else range(6))], out, args.workers,
                            fn=default_case)
    print(bl.summarise([dict(r, profile="thermal") for r in rows]))


if __name__ == "__main__":
    main()
