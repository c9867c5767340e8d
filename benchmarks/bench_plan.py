"""Check ``fogbayes plan`` by simulation: do records of the planned length reach the target?

For each noise mix of ``coverage_allan.py`` (A: tactical FOG at 10 Hz; B: MEMS-like at
100 Hz) and each target (K +-10 %, N +-1 %, B +-10 %, all at 90 %):

1. a 1 h pilot (seed 0) is planned from (:func:`fogbayes.plan.plan_from_pilot`): point plan
   and range over the pilot's joint 90 % region (unresolved terms other than R at their
   upper bound for the long end); the plan from the true values
   (:func:`fogbayes.plan.plan_length`) is given beside it;
2. ``--records`` records of the pilot-planned length and of the truth-planned length
   (seeds 1000, 1001, ...) are simulated and fitted by GLS on the plan's model
   (``fit_range(data, model)``) and, as ``fogbayes allan`` does, on all five terms; the
   achieved relative half-width sinh(1.645 se_log) of the target term -- the definition
   the plan uses -- is reported (median, mean, 10-90 %), with the coverage of the truth by
   the fit's 90 % interval and the share of records whose estimate is within the target of
   the truth;
3. ``--pilots`` pilots (seeds 0, 1, ...) are planned from to show how the plan varies with
   the pilot (refusals: the pilot did not resolve the term).

Records: the simulator's flicker noise has no power below 1/length, so (as in
``coverage_allan.py``) it is drawn over a longer span and its first ``n`` samples kept: here
the next power of two >= 4 n (an FFT of 4 n samples of awkward size costs ~5x more); the
quantization, white and random-walk parts are drawn at ``n`` samples with the same
functions (:mod:`fogbayes.simulate.noise`), which is the distribution of
``allan_noise(4 n, ...)[:n]``. Pilots are ``allan_noise(4 n, ...)[:n]`` exactly.

    python benchmarks/bench_plan.py                       # ~10 min on 2 cores
    python benchmarks/bench_plan.py --records 10 --pilots 4 --mixes A   # quick look
"""

from __future__ import annotations

import argparse
import json
import math
import multiprocessing
import os
import platform
import time
from concurrent.futures import ProcessPoolExecutor

import numpy as np

import fogbayes  # noqa: F401  (float64)
from fogbayes.allan.data import prepare
from fogbayes.allan.fit import fit_range
from fogbayes.allan.model import TERMS, AllanParams
from fogbayes.plan import PlanError, half_width, plan_from_pilot, plan_length, predicted_width
from fogbayes.simulate.noise import (allan_noise, flicker_noise, quantization_noise,
                                     random_walk_noise, white_noise)

MIXES = {
    "A": (10.0, dict(Q=0.19, N=0.01, B=0.165, K=0.66)),
    "B": (100.0, dict(Q=0.775, N=0.1, B=2.02, K=11.4)),
}
TARGETS = (("K", 0.10), ("N", 0.01), ("B", 0.10))
LEVEL = 0.9
PILOT_S = 3600.0
RECORD_SEED0 = 1000


def record(mix: str, n: int, seed: int) -> np.ndarray:
    """A record of n samples (module docstring: flicker drawn over >= 4 n samples)."""
    fs, p = MIXES[mix]
    span = 1 << (4 * n - 1).bit_length()
    return (quantization_noise(n, fs, seed=seed, Q=p["Q"]) + white_noise(n, fs, seed=seed, N=p["N"])
            + flicker_noise(span, fs, seed=seed, B=p["B"], span=1)[:n]
            + random_walk_noise(n, fs, seed=seed, K=p["K"]))


def pilot(mix: str, seed: int) -> tuple[np.ndarray, float]:
    fs, p = MIXES[mix]
    n = int(PILOT_S * fs)
    return allan_noise(4 * n, fs, seed=seed, flicker_span=1, **p)[:n], fs


def fit_one(args) -> dict:
    """Simulate and fit one record; the target term's estimate, interval and half-width."""
    mix, n, seed, term, model = args
    fs, truth = MIXES[mix]
    t0 = time.perf_counter()
    data = prepare(record(mix, n, seed), fs)
    out = {"mix": mix, "n": n, "seed": seed, "term": term}
    for name, terms in (("model", tuple(model)), ("five", TERMS)):
        _, fit, dropped = fit_range(data, terms)
        e = fit.terms[term]
        se = float(fit.info["se_log"][TERMS.index(term)])
        out[name] = {"value": e.value, "low": e.low, "high": e.high,
                     "width": float(half_width(se, LEVEL)), "dropped_taus": dropped,
                     "converged": fit.converged}
    out["truth"] = truth[term]
    out["seconds"] = time.perf_counter() - t0
    return out


def plan_one(args) -> dict:
    """Plan from one pilot; hours of the point plan and of the range (None = refused), and
    the width the true noise gives at the point plan's and the range's long end's length
    (predicted_width at the truth, which records of that length achieve to within 0.3
    points: section 2 of RESULTS_plan.md)."""
    mix, seed, term, prec = args
    y, fs = pilot(mix, seed)
    t0 = time.perf_counter()
    try:
        pp = plan_from_pilot(y, fs, term, prec, level=LEVEL)
    except PlanError as exc:
        return {"mix": mix, "seed": seed, "term": term, "refused": str(exc),
                "seconds": time.perf_counter() - t0}
    truth = AllanParams(**MIXES[mix][1])
    at_truth = {k: None if n is None else predicted_width(truth, fs, n, term, level=LEVEL,
                                                          terms=("Q", "N", "B", "K"))
                for k, n in (("plan", pp.plan.n), ("range_high", pp.range.n_high))}
    return {"mix": mix, "seed": seed, "term": term, "refused": None, "n": pp.plan.n,
            "width_at_truth": at_truth,
            "hours": pp.plan.hours, "range": list(pp.range_hours), "model": list(pp.terms),
            "range_n": [pp.range.n_low, pp.range.n_high],
            "pilot": {t: list(e[:3]) for t, e in pp.fit.terms.items()},
            "ends": {t: {w: (v, None if one is None else one.hours) for w, (v, one) in e.items()}
                     for t, e in pp.ends.items()},
            "seconds": time.perf_counter() - t0}


def summarise(rows: list[dict], name: str, prec: float) -> dict:
    w = np.array([r[name]["width"] for r in rows])
    err = np.array([abs(r[name]["value"] / r["truth"] - 1.0) for r in rows])
    cov = np.mean([r[name]["low"] <= r["truth"] <= r[name]["high"] for r in rows])
    return {"median": float(np.median(w)), "mean": float(np.mean(w)),
            "p10": float(np.quantile(w, 0.1)), "p90": float(np.quantile(w, 0.9)),
            "coverage": float(cov), "within": float(np.mean(err <= prec)),
            "err_p90": float(np.quantile(err, 0.9)),
            "low0": int(sum(r[name]["low"] <= 0 for r in rows)), "count": len(rows)}


def fmt_h(h) -> str:
    return "refused" if h is None else ("> 1000 d" if not math.isfinite(h) else f"{h:.3g}")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--records", type=int, default=50,
                    help="records per planned length (0: plans only, sections 1 and 3)")
    ap.add_argument("--targets", default="K,N,B", help="which of K, N, B to plan for")
    ap.add_argument("--pilots", type=int, default=20)
    ap.add_argument("--mixes", default="A,B")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--out", default=None, help="also write the raw rows as JSON")
    args = ap.parse_args()
    t_start = time.perf_counter()
    mixes = args.mixes.split(",")
    targets = [tp for tp in TARGETS if tp[0] in args.targets.split(",")]
    # spawn, not fork: JAX's threads in the parent would make forked workers deadlock-prone
    pool = ProcessPoolExecutor(args.workers, mp_context=multiprocessing.get_context("spawn"))
    print(f"# bench_plan: {platform.machine()}, {os.cpu_count()} cores, workers "
          f"{args.workers}, records {args.records}, pilots {args.pilots}")

    # 1-2: the seed-0 pilot's plans, the truth plans, records of both lengths
    heads, jobs = [], []
    for mix in mixes:
        fs, truth = MIXES[mix]
        for term, prec in targets:
            head = plan_one((mix, 0, term, prec))
            tp = plan_length(AllanParams(**truth), fs, term, prec, level=LEVEL,
                             terms=("Q", "N", "B", "K"))
            head.update(truth_n=tp.n, truth_hours=tp.hours, prec=prec)
            heads.append(head)
            model = head["model"] if head["refused"] is None else ["Q", "N", "B", "K"]
            lengths = {"truth plan": tp.n}
            if head["refused"] is None:
                lengths = {"pilot plan": head["n"], **lengths}
            head["lengths"] = lengths
            if head["refused"] is None:  # what recording the range's long end would give
                nh = head["range_n"][1]
                head["truth_width_at_range_high"] = None if nh is None else predicted_width(
                    AllanParams(**truth), fs, nh, term, level=LEVEL, terms=("Q", "N", "B", "K"))
            head["predicted_at_truth"] = {
                k: predicted_width(AllanParams(**truth), fs, n, term, level=LEVEL,
                                   terms=("Q", "N", "B", "K")) for k, n in lengths.items()}
            for kind, n in lengths.items():
                jobs.append(((mix, term, kind), [(mix, n, RECORD_SEED0 + i, term, model)
                                                 for i in range(args.records)]))
    futures = [(key, [pool.submit(fit_one, a) for a in batch]) for key, batch in jobs]
    pilot_jobs = [pool.submit(plan_one, (mix, s, term, prec)) for mix in mixes
                  for term, prec in targets for s in range(args.pilots)]
    results = {key: [f.result() for f in fs_] for key, fs_ in futures}
    pilots = [f.result() for f in pilot_jobs]
    pool.shutdown()

    print("\n## Plans from the seed-0 1 h pilot (hours) and from the true values\n")
    print("| mix | target | pilot estimate [90 %] | pilot plan h | range h (joint 90 %) | "
          "truth plan h | width at the range's long end (truth) |")
    print("|---|---|---|---|---|---|---|")
    for h in heads:
        t = h["term"]
        if h["refused"] is None:
            v, lo, hi = h["pilot"][t]
            wh = h["truth_width_at_range_high"]
            print(f"| {h['mix']} | {t} +-{h['prec']:.0%} | {v:.4g} [{lo:.4g}, {hi:.4g}] | "
                  f"{h['hours']:.3g} | {fmt_h(h['range'][0])} - {fmt_h(h['range'][1])} | "
                  f"{h['truth_hours']:.3g} | {'-' if wh is None else f'{wh:.2%}'} |")
        else:
            print(f"| {h['mix']} | {t} +-{h['prec']:.0%} | not resolved | refused | - | "
                  f"{h['truth_hours']:.3g} | - |")

    summary = []
    if args.records:
        summary = achieved(heads, results, args.records)
    pilots_table(pilots, heads, mixes, targets, args.pilots)
    total = time.perf_counter() - t_start
    rec_s = [r["seconds"] for rows in results.values() for r in rows] or [0.0]
    plan_s = [p["seconds"] for p in pilots]
    print(f"\n{len(results) and sum(map(len, results.values()))} records (mean "
          f"{np.mean(rec_s):.1f} s each: simulate, prepare, 2 fits), "
          f"{len(pilots)} pilot plans (mean {np.mean(plan_s):.1f} s, max {np.max(plan_s):.1f} s); "
          f"total {total:.0f} s wall")
    if args.out:
        with open(args.out, "w") as f:
            json.dump({"heads": heads, "summary": summary, "pilots": pilots,
                       "records": {"|".join(k): v for k, v in results.items()}}, f)


def achieved(heads, results, records) -> list[dict]:
    """Section 2: the widths records of the planned lengths achieve."""
    print("\n## Achieved on simulated records of the planned length "
          f"({records} records each, seeds {RECORD_SEED0}-{RECORD_SEED0 + records - 1})\n")
    print("width = (high - low) / (2 value) = sinh(1.645 se_log); within = share of records "
          "with |estimate / truth - 1| <= target; cover = truth inside the fit's 90 % interval\n")
    print("| mix | target | length | h | predicted width at truth | plan model: width median / "
          "mean (10-90 %) | cover | within | five terms: width median / mean | cover | low = 0 |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    summary = []
    for h in heads:
        for kind, n in h["lengths"].items():
            rows = results[(h["mix"], h["term"], kind)]
            a, b = summarise(rows, "model", h["prec"]), summarise(rows, "five", h["prec"])
            fs = MIXES[h["mix"]][0]
            summary.append({"mix": h["mix"], "term": h["term"], "length": kind, "n": n,
                            "model": a, "five": b})
            print(f"| {h['mix']} | {h['term']} +-{h['prec']:.0%} | {kind} | {n / fs / 3600:.3g} | "
                  f"{h['predicted_at_truth'][kind]:.2%} | {a['median']:.2%} / {a['mean']:.2%} "
                  f"({a['p10']:.1%}-{a['p90']:.1%}) | {a['coverage']:.0%} | {a['within']:.0%} | "
                  f"{b['median']:.2%} / {b['mean']:.2%} | {b['coverage']:.0%} | {b['low0']} |")
    return summary


def pilots_table(pilots, heads, mixes, targets, n_pilots) -> None:
    """Section 3: how the plan varies with the pilot."""
    print(f"\n## How the plan varies with the pilot ({n_pilots} pilots of 1 h, seeds 0-"
          f"{n_pilots - 1})\n")
    print("| mix | target | refused | point plan h: median (min - max) | joint range covers "
          "the truth plan | median range h | one-at-a-time ends cover it | width the truth "
          "gives at the point plan: median (10-90 %) | share within target +-30 % | the same "
          "at the range's long end |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for mix in mixes:
        for term, prec in targets:
            sel = [p for p in pilots if p["mix"] == mix and p["term"] == term]
            ok = [p for p in sel if p["refused"] is None]
            truth_h = next(h["truth_hours"] for h in heads
                           if h["mix"] == mix and h["term"] == term)
            if not ok:
                print(f"| {mix} | {term} +-{prec:.0%} | {len(sel)} of {len(sel)} | - | - | - | - "
                      "| - | - | - |")
                continue
            hs = np.array([p["hours"] for p in ok])
            cover = np.mean([p["range"][0] <= truth_h <= p["range"][1] for p in ok])
            ends = [[h_ for e in p["ends"].values() for _, h_ in e.values()] + [p["hours"]]
                    for p in ok]
            ends = [[math.inf if x is None else x for x in e] for e in ends]
            cover1 = np.mean([min(e) <= truth_h <= max(e) for e in ends])
            lo = np.median([p["range"][0] for p in ok])
            hi = np.median([p["range"][1] for p in ok])
            cols = []
            for k in ("plan", "range_high"):  # the done-when's band: target +- 3 points of 10
                w = np.array([math.inf if p["width_at_truth"][k] is None
                              else p["width_at_truth"][k] for p in ok])
                band = np.mean(np.abs(w / prec - 1.0) <= 0.3)
                cols.append(f"{np.median(w):.2%} ({np.quantile(w, 0.1):.1%}-"
                            f"{np.quantile(w, 0.9):.1%})" + (f" | {band:.0%}" if k == "plan" else ""))
            print(f"| {mix} | {term} +-{prec:.0%} | {len(sel) - len(ok)} of {len(sel)} | "
                  f"{np.median(hs):.3g} ({hs.min():.3g} - {hs.max():.3g}) | "
                  f"{cover:.0%} ({len(ok)}) | {fmt_h(lo)} - {fmt_h(hi)} | {cover1:.0%} | "
                  + " | ".join(cols) + " |")


if __name__ == "__main__":
    main()
