"""Pooled thermal bias laws on simulated fleets with a known population (issue #26).

    python benchmarks/bench_pool_thermal.py [--fleets 40] [--units 20] [--workers 2]
                                            [--out benchmarks/pool_thermal.json]

Each fleet: ``--units`` sensors of one type, each a 1 h, 1 Hz generic chamber test
(``simulate("thermal")``: -20..60 deg C, the scenario's noise N 0.005, B 0.02, K 0.02) whose
bias law is ``a0 + a1 (T - 20) + a2 (T - 20)^2`` with (a0, a1, a2) drawn from the population
N(MU, diag(SD^2)); SD is of the order of one unit's own standard errors, so pooling has
something to do. Unit 0 of every fleet is an outlier: its a0 is MU + OUTLIER_SD x SD
(``--outlier-sd``; 0: no outlier, the fleets for the population's coverage). Each
unit is fitted by :func:`fogbayes.pool.thermal.fit_unit` (GLS under its noise model), the
fleet pooled by :func:`fogbayes.pool.thermal.pool_thermal`.

Reported: coverage of the population means' and spreads' 90 % intervals (fleets with the
outlier left out of the truth: the population's MU and SD), the RMS error of each unit's
pooled against its unpooled estimate (units 1.., against their true values), the outlier's
flag rate and the false-flag rate among units 1... Rows per fleet go to ``--out``.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))

MU = np.array([0.5, 0.01, 2e-4])
SD = np.array([0.02, 5e-4, 2e-5])
OUTLIER_SD = 5.0
DEFAULT_OUT = os.path.join(HERE, "pool_thermal.json")


def one_fleet(fleet: int, n_units: int, outlier_sd: float = OUTLIER_SD) -> dict:
    from fogbayes.pool.thermal import fit_unit, pool_thermal
    from fogbayes.simulate import simulate

    rng = np.random.default_rng(1000 + fleet)
    truth = MU + SD * rng.standard_normal((n_units, 3))
    if outlier_sd:
        truth[0, 0] = MU[0] + outlier_sd * SD[0]
    t0 = time.perf_counter()
    units = []
    for u in range(n_units):
        sim = simulate("thermal", seed=10_000 * fleet + u, duration=3600.0, fs=1.0,
                       effects={"temperature_order": {"coeffs": list(truth[u]), "T_ref": 20.0}})
        units.append(fit_unit(sim.recording, name=f"u{u}"))
    t_fit = time.perf_counter() - t0
    doc = pool_thermal(units, seed=fleet)
    pop = doc["population"]
    terms = doc["terms"]
    single = np.array([[r["terms"][t]["single"]["value"] for t in terms] for r in doc["units"]])
    pooled = np.array([[r["terms"][t]["pooled"]["value"] for t in terms] for r in doc["units"]])
    return {"fleet": fleet, "units": n_units, "converged": doc["converged"],
            "mean_covered": [pop[t]["mean"]["low"] <= MU[j] <= pop[t]["mean"]["high"]
                             for j, t in enumerate(terms)],
            "spread_covered": [pop[t]["spread_sd"]["low"] <= SD[j] <= pop[t]["spread_sd"]["high"]
                               for j, t in enumerate(terms)],
            "mean": [pop[t]["mean"]["value"] for t in terms],
            "sq_err_single": ((single[1:] - truth[1:]) ** 2).sum(0).tolist(),
            "sq_err_pooled": ((pooled[1:] - truth[1:]) ** 2).sum(0).tolist(),
            "outlier_flagged": doc["units"][0]["outlier"]["flagged"],  # a clean unit when outlier_sd is 0
            "false_flags": sum(r["outlier"]["flagged"] for r in doc["units"][1:]),
            "seconds_fit": t_fit, "seconds": time.perf_counter() - t0}


def summarise(rows: list[dict]) -> dict:
    F = len(rows)
    U = rows[0]["units"] - 1
    cov_mean = np.mean([r["mean_covered"] for r in rows], axis=0)
    cov_spread = np.mean([r["spread_covered"] for r in rows], axis=0)
    rms_s = np.sqrt(np.sum([r["sq_err_single"] for r in rows], axis=0) / (F * U))
    rms_p = np.sqrt(np.sum([r["sq_err_pooled"] for r in rows], axis=0) / (F * U))
    return {"fleets": F, "units_per_fleet": U + 1,
            "coverage_mean_90": dict(zip(("a0", "a1", "a2"), cov_mean.round(3).tolist())),
            "coverage_spread_90": dict(zip(("a0", "a1", "a2"), cov_spread.round(3).tolist())),
            "rms_pooled_over_single": dict(zip(("a0", "a1", "a2"),
                                               (rms_p / rms_s).round(3).tolist())),
            "outlier_flagged": f"{sum(r['outlier_flagged'] for r in rows)}/{F}",
            "false_flags": f"{sum(r['false_flags'] for r in rows)}/{F * U}",
            "converged": f"{sum(r['converged'] for r in rows)}/{F}",
            "median_seconds_per_fleet": float(np.median([r["seconds"] for r in rows]))}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--fleets", type=int, default=40)
    ap.add_argument("--units", type=int, default=20)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--out", default=DEFAULT_OUT)
    ap.add_argument("--outlier-sd", type=float, default=OUTLIER_SD,
                    help="unit 0's a0 offset in population sd (0: no outlier)")
    args = ap.parse_args()
    with ProcessPoolExecutor(args.workers) as ex:
        rows = list(ex.map(one_fleet, range(args.fleets), [args.units] * args.fleets,
                           [args.outlier_sd] * args.fleets))
    summary = summarise(rows)
    from fogbayes.support.jsonable import to_jsonable

    with open(args.out, "w") as f:
        json.dump(to_jsonable({"MU": MU.tolist(), "SD": SD.tolist(), "outlier_sd": args.outlier_sd,
                               "summary": summary, "rows": rows}), f, indent=1)
    print(json.dumps(summary, indent=1))


if __name__ == "__main__":
    main()
