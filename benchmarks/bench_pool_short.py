"""Pools of a few short static units against simulation truth (benchmarks/RESULTS_pool.md).

Each repetition pools ``--units`` records of ``fogbayes simulate static`` (1 h; true
N 0.005 deg/sqrt(h), B 0.02 deg/h, K 0.05 deg/h^1.5, the same for every unit: a spread of 0),
seeds ``first + units * rep`` onwards, as ``fogbayes pool`` does (``pool_allan``, default
sampler). Per pooled term it records whether the population resolves it and whether the
truth lies in what is stated: the 90 % interval of the population median, or [0, bound]
for an upper bound (95 %).

    python benchmarks/bench_pool_short.py --reps 5 --units 4 --first 11 --out pool_short.json
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np


def one(seeds, fs):
    from fogbayes.pool.allan import fit_unit, pool_allan
    from fogbayes.simulate import simulate

    units, truth = [], None
    for s in seeds:
        sim = simulate("static", seed=int(s), fs=fs)
        truth = sim.truth.params["noise"]
        units.append(fit_unit(sim.recording, name=f"seed {s}"))
    doc = pool_allan(units, seed=0)
    out = {"seeds": [int(s) for s in seeds], "converged": doc["converged"], "terms": {}}
    for t in doc["terms"]:
        p, true = doc["population"][t], float(truth[t])
        m = p["median"]
        if p["resolved"]:
            covered = m["low"] <= true <= m["high"]
            stated = [m["low"], m["value"], m["high"]]
        else:
            covered = true <= m["upper"]
            stated = [0.0, None, m["upper"]]
        out["terms"][t] = {"truth": true, "resolved": p["resolved"], "stated": stated,
                           "covered": bool(covered),
                           "units_resolving": sum(u["terms"][t]["single"]["resolved"]
                                                  for u in doc["units"])}
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--reps", type=int, default=5)
    ap.add_argument("--units", type=int, default=4)
    ap.add_argument("--first", type=int, default=11)
    ap.add_argument("--fs", type=float, default=None, help="Hz (default: the scenario's 10)")
    ap.add_argument("--out", default=None)
    a = ap.parse_args()
    rows = []
    for rep in range(a.reps):
        t0 = time.time()
        seeds = a.first + a.units * rep + np.arange(a.units)
        rows.append(one(seeds, a.fs))
        r = rows[-1]
        print(f"seeds {r['seeds']}: " + "; ".join(
            f"{t} {'interval' if v['resolved'] else 'bound'} "
            f"{', '.join('-' if x is None else f'{x:.3g}' for x in v['stated'])} "
            f"(truth {v['truth']:g}: {'in' if v['covered'] else 'OUT'})"
            for t, v in r["terms"].items()) + f"  [{time.time() - t0:.0f} s]", flush=True)
    for t in rows[0]["terms"]:
        cov = np.mean([r["terms"][t]["covered"] for r in rows])
        res = np.mean([r["terms"][t]["resolved"] for r in rows])
        print(f"{t}: truth within what is stated in {cov:.0%} of {len(rows)} pools; "
              f"resolved in {res:.0%}")
    if a.out:
        with open(a.out, "w") as f:
            json.dump({"args": vars(a), "pools": rows}, f, indent=1)


if __name__ == "__main__":
    main()
