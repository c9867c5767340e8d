"""Pooled fleets with a known population: coverage, shrinkage gain, outlier flags.

Each repetition simulates a fleet of ``--units`` sensors of one type: unit u has
log N_u, log B_u, log K_u drawn from normal populations about N0, B0, K0 with spreads
SPREAD (log sd), and one static record of ``--log2n`` samples at FS. Every record is fitted
alone (GLS, as ``fogbayes allan``) and the fleet is pooled (:func:`fogbayes.pool.allan.pool_allan`).
Counted over repetitions:

* coverage of the 90 % intervals of the population medians N0, B0, K0 and of the spreads;
* RMS log error of the per-unit estimates, pooled (posterior median) against unpooled (the
  unit's own GLS fit), and the coverage of the pooled per-unit intervals;
* false flags: clean units flagged at the flag level (every unit of the clean fleet);
* detection: the same fleet with unit 0's record replaced by an outlier (its K times
  ``--outlier-k``), pooled again: is unit 0 flagged?

The simulator's flicker noise lacks power below 1/T, so each record is simulated 4x longer
and its first quarter kept (as benchmarks/coverage_allan.py does).

    python benchmarks/bench_pool.py --reps 100 --out benchmarks/pool_fleet.json
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

import fogbayes  # noqa: F401  (float64)
from fogbayes.pool.allan import FLAG_LEVEL, pool_allan, unit_from_fit
from fogbayes.simulate.noise import allan_noise

FS = 10.0
#: population medians: mix A of coverage_allan.py (a tactical FOG at 10 Hz)
POP = {"Q": 0.19, "N": 0.01, "B": 0.165, "K": 0.66}
SPREAD = {"N": 0.15, "B": 0.3, "K": 0.3}
TERMS = ("N", "B", "K")


def fit_record(y, name):
    from fogbayes.allan.data import prepare
    from fogbayes.allan.fit import fit_range

    data, fit, left = fit_range(prepare(y, FS))
    return unit_from_fit(name, None, y.size, FS, data, fit, left)


def unit_truth(rng):
    return {t: POP[t] * (np.exp(SPREAD[t] * rng.standard_normal()) if t in SPREAD else 1.0)
            for t in POP}


def simulate(truth, n, seed):
    return allan_noise(4 * n, FS, seed=seed, flicker_span=1, **truth)[:n]


def one_rep(rep, args):
    rng = np.random.default_rng(10_000 + rep)
    n = 2 ** args.log2n
    truths = [unit_truth(rng) for _ in range(args.units)]
    units = [fit_record(simulate(tr, n, seed=100_000 * rep + u), f"u{u}")
             for u, tr in enumerate(truths)]
    doc = pool_allan(units, terms=TERMS, seed=rep, flag_level=args.flag_level,
                     covariance_at=args.covariance_at, outlier_test=args.outlier_test)
    out = {"rep": rep, "converged": doc["converged"], "population": {}, "units": {}}
    for t in TERMS:
        p = doc["population"][t]
        s = p["spread"]["log_sd"]
        out["population"][t] = {
            "covered": bool(p["median"]["low"] <= POP[t] <= p["median"]["high"]),
            "spread_covered": bool(s["low"] <= SPREAD[t] <= s["high"]),
            "log_error": float(np.log(p["median"]["value"] / POP[t]))}
        true = np.log([tr[t] for tr in truths])
        single = np.log([max(u["terms"][t]["single"]["value"], 1e-300) for u in doc["units"]])
        pooled = np.log([u["terms"][t]["pooled"]["value"] for u in doc["units"]])
        cover = [u["terms"][t]["pooled"]["low"] <= tr[t] <= u["terms"][t]["pooled"]["high"]
                 for u, tr in zip(doc["units"], truths)]
        out["units"][t] = {"sse_single": float(np.sum((single - true) ** 2)),
                           "sse_pooled": float(np.sum((pooled - true) ** 2)),
                           "pooled_covered": int(sum(cover))}
    out["false_flags"] = int(sum(u["outlier"]["flagged"] for u in doc["units"]))
    out["clean_p"] = [float(u["outlier"]["p"]) for u in doc["units"]]  # for other flag levels
    out["unresolved"] = sum(w.startswith(tuple(TERMS)) for w in doc["warnings"])
    bad = dict(truths[0])
    bad["K"] = bad["K"] * args.outlier_k
    units[0] = fit_record(simulate(bad, n, seed=100_000 * rep + 99_999), "u0")
    doc2 = pool_allan(units, terms=TERMS, seed=rep, flag_level=args.flag_level,
                     covariance_at=args.covariance_at, outlier_test=args.outlier_test)
    out["outlier_flagged"] = bool(doc2["units"][0]["outlier"]["flagged"])
    out["outlier_p"] = float(doc2["units"][0]["outlier"]["p"])
    out["false_flags_with_outlier"] = int(sum(u["outlier"]["flagged"] for u in doc2["units"][1:]))
    out["beside_p"] = [float(u["outlier"]["p"]) for u in doc2["units"][1:]]
    return out


def summarise(rows, args) -> dict:
    R, U = len(rows), args.units
    s = {"reps": R, "units": U, "log2n": args.log2n, "hours": 2 ** args.log2n / FS / 3600,
         "flag_level": args.flag_level, "outlier_k": args.outlier_k,
         "converged": sum(r["converged"] for r in rows)}
    for t in TERMS:
        s[t] = {"population_coverage": np.mean([r["population"][t]["covered"] for r in rows]),
                "spread_coverage": np.mean([r["population"][t]["spread_covered"] for r in rows]),
                "population_rms_log_error": float(np.sqrt(np.mean(
                    [r["population"][t]["log_error"] ** 2 for r in rows]))),
                "unit_rms_single": float(np.sqrt(sum(r["units"][t]["sse_single"] for r in rows) / (R * U))),
                "unit_rms_pooled": float(np.sqrt(sum(r["units"][t]["sse_pooled"] for r in rows) / (R * U))),
                "unit_pooled_coverage": sum(r["units"][t]["pooled_covered"] for r in rows) / (R * U)}
        s[t]["rms_ratio_pooled_over_single"] = s[t]["unit_rms_pooled"] / s[t]["unit_rms_single"]
    s["false_flag_rate"] = sum(r["false_flags"] for r in rows) / (R * U)
    s["false_flag_rate_beside_outlier"] = sum(r["false_flags_with_outlier"] for r in rows) / (R * (U - 1))
    s["outlier_detection"] = float(np.mean([r["outlier_flagged"] for r in rows]))
    if all("clean_p" in r for r in rows):  # the operating curve: detection vs false flags
        clean = np.concatenate([r["clean_p"] for r in rows])
        out_p = np.array([r["outlier_p"] for r in rows])
        s["operating"] = {str(lv): {"detection": float(np.mean(out_p < lv)),
                                    "false_flag_rate": float(np.mean(clean < lv))}
                          for lv in (0.001, 0.005, 0.01, 0.02, 0.05)}
    return s


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--reps", type=int, default=100)
    ap.add_argument("--first-rep", type=int, default=0)
    ap.add_argument("--units", type=int, default=20)
    ap.add_argument("--log2n", type=int, default=17)
    ap.add_argument("--flag-level", type=float, default=FLAG_LEVEL)
    ap.add_argument("--outlier-k", type=float, default=5.0)
    ap.add_argument("--covariance-at", choices=("population", "estimate"), default="population",
                    help="where each unit's covariance is evaluated (fogbayes.pool.allan.pool_allan)")
    ap.add_argument("--outlier-test", choices=("each", "joint"), default="each")
    ap.add_argument("--out", default=None)
    args = ap.parse_args()
    rows, t0 = [], time.perf_counter()
    for rep in range(args.first_rep, args.first_rep + args.reps):
        rows.append(one_rep(rep, args))
        if (rep + 1) % 10 == 0:
            print(f"{rep + 1} reps, {time.perf_counter() - t0:.0f} s", flush=True)
            if args.out:  # a run cut short keeps its rows
                with open(args.out, "w") as fh:
                    json.dump({"rows": rows}, fh, default=float)
    s = summarise(rows, args)
    s["seconds"] = time.perf_counter() - t0
    print(json.dumps(s, indent=1, default=float))
    if args.out:
        with open(args.out, "w") as fh:
            json.dump({"summary": s, "rows": rows}, fh, indent=1, default=float)


if __name__ == "__main__":
    main()
