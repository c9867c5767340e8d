"""A short run with and without a datasheet prior (``fogbayes allan --bayes --prior``).

Simulates short records of mix A (benchmarks/coverage_allan.py: a tactical FOG at 10 Hz,
Q = 0.19 arcsec, N = 0.01 deg/sqrt(h), B = 0.165 deg/h, K = 0.66 deg/h^1.5; default
20 min), fits each with the NumPyro posterior without and with a datasheet prior, and
reports per term N, B, K: the coverage of the 90 % interval, the median relative width
(high - low) / truth, and the RMS log error sqrt(mean(log(median / truth)^2)); then the
bias (mean log(median / truth)) and the median ratio high / low of the interval.

The datasheet is the truth times an error ``--factor`` (1.5: a sheet 50 % pessimistic on
every term), written in datasheet units and converted by :func:`build_prior` (ARW in
deg/h/sqrt(Hz), bias instability as the ADEV floor 0.6643 B in deg/h, RRW in deg/h/sqrt(h)),
looseness ``--looseness`` (3). ``--extra-factors`` adds sheets off by other factors (the
five-term posterior only).

Two fits are compared:

* ``posterior``: :func:`fit_bayes` with all five terms (no selection);
* ``cli``: what ``fogbayes allan --bayes [--prior]`` does (:func:`fit_recording`, term
  selection by PSIS-LOO); a term it drops is reported as value 0 with the interval
  [0, 95 % quantile]: its RMS log error is over the records that kept it.

As in coverage_allan.py the simulator's flicker has no power below 1/T, so 4 x the record
is simulated and the first quarter kept.

    python benchmarks/bench_datasheet_prior.py --seeds 20 --extra-factors 0.6667,3 \
        --out prior_rows.json
    python benchmarks/bench_datasheet_prior.py --rows prior_rows.json   # tables again

Run time: ~18 s a seed on an idle 2-core box (~7 min for 20 seeds with the extra sheets);
17 min under the load of 2026-11-25 (load average ~5).
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

import fogbayes  # noqa: F401  (float64)
from fogbayes import Recording
from fogbayes.data import Metadata
from fogbayes.allan import bayes as ab
from fogbayes.allan.data import prepare
from fogbayes.allan.fit import fit_range
from fogbayes.inference.datasheet import build_prior
from fogbayes.allan.model import BI_FACTOR
from fogbayes.simulate.noise import allan_noise
from fogbayes.allan.workflow import fit_recording

FS = 10.0
TRUTH = dict(Q=0.19, N=0.01, B=0.165, K=0.66)
PARAMS = ("N", "B", "K")


def sheet(factor: float, looseness: float):
    """The datasheet of a sensor whose every number is ``factor`` x the truth, in the units
    datasheets use (ARW deg/h/sqrt(Hz), bias instability = ADEV floor in deg/h, RRW)."""
    return build_prior(arw=60.0 * TRUTH["N"] * factor, arw_unit="deg/h/sqrt(Hz)",
                       bias_instability=BI_FACTOR * TRUTH["B"] * factor,
                       bias_instability_unit="deg/h", rrw=TRUTH["K"] * factor,
                       rrw_unit="deg/h/sqrt(h)", looseness=looseness,
                       sensor=f"simulated mix A, sheet = truth x {factor:g}")


def _terms(fit_terms) -> dict:
    return {p: [float(x) for x in fit_terms[p][:3]] for p in PARAMS}


def one(seed: int, n: int, factors: list[float], looseness: float, cli: bool) -> dict:
    y = allan_noise(4 * n, FS, seed=seed, flicker_span=1, **TRUTH)[:n]
    data, _, _ = fit_range(prepare(y, FS))
    row = {"seed": seed, "n": n}
    for k, factor in enumerate([None] + factors):
        prior = None if factor is None else sheet(factor, looseness)
        name = "none" if factor is None else f"x{factor:g}"
        t0 = time.perf_counter()
        post = ab.fit_bayes(data, seed=seed, prior=prior)
        row[f"posterior/{name}"] = {"terms": _terms(post.fit.terms),
                                    "converged": post.diagnostics["converged"],
                                    "seconds": time.perf_counter() - t0}
        if cli and k <= 1:  # the command line's path: no prior and the main sheet
            rec = Recording(time=np.arange(n) / FS, output=y, unit="deg/h",
                            meta=Metadata(sensor_id=f"sim-{seed}", sample_rate=FS))
            t0 = time.perf_counter()
            doc = fit_recording(rec, bayes=True, seed=seed, prior=prior)
            terms = doc["fit"]["terms"]
            row[f"cli/{name}"] = {
                "terms": {p: [terms[p]["value"], terms[p]["low"], terms[p]["high"]]
                          for p in PARAMS},
                "present": [p for p in PARAMS if terms[p]["present"]],
                "converged": doc["converged"], "seconds": time.perf_counter() - t0}
    return row


def summarize(rows: list[dict]) -> str:
    methods = [k for k in rows[0] if "/" in k]
    head = ("| fit | prior | conv. | s/fit | "
            + " | ".join(f"{p} cover" for p in PARAMS) + " | "
            + " | ".join(f"{p} width" for p in PARAMS) + " | "
            + " | ".join(f"{p} RMS log err" for p in PARAMS) + " |")
    lines = [head, "|" + "---|" * (4 + 3 * len(PARAMS))]
    for m in methods:
        res = [r[m] for r in rows]
        cover, width, rms = [], [], []
        for p in PARAMS:
            t = TRUTH[p]
            est = np.array([r["terms"][p] for r in res])
            cover.append(f"{np.mean((est[:, 1] <= t) & (t <= est[:, 2])):.0%}")
            width.append(f"{np.median((est[:, 2] - est[:, 1]) / t):.2f}")
            kept = est[est[:, 0] > 0, 0]
            err = np.sqrt(np.mean(np.log(kept / t) ** 2)) if kept.size else float("nan")
            rms.append(f"{err:.3f}" + ("" if kept.size == len(res) else
                                       f" ({kept.size} kept)"))
        conv = np.mean([r["converged"] for r in res])
        sec = np.mean([r["seconds"] for r in res])
        fit, prior = m.split("/")
        lines.append(f"| {fit} | {prior} | {conv:.0%} | {sec:.1f} | " + " | ".join(cover)
                     + " | " + " | ".join(width) + " | " + " | ".join(rms) + " |")
    lines += ["", "| fit | prior | " + " | ".join(f"{p} bias" for p in PARAMS) + " | "
              + " | ".join(f"{p} high/low" for p in PARAMS) + " |",
              "|" + "---|" * (2 + 2 * len(PARAMS))]
    for m in methods:  # bias = mean log(median / truth) over kept terms; high/low: median
        res = [r[m] for r in rows]
        bias, ratio = [], []
        for p in PARAMS:
            est = np.array([r["terms"][p] for r in res])
            kept = est[est[:, 0] > 0]
            bias.append(f"{np.mean(np.log(kept[:, 0] / TRUTH[p])):+.3f}" if kept.size else "-")
            ratio.append(f"{np.median(kept[:, 2] / kept[:, 1]):.3g}" if kept.size else "-")
        fit, prior = m.split("/")
        lines.append(f"| {fit} | {prior} | " + " | ".join(bias) + " | " + " | ".join(ratio)
                     + " |")
    return "\n".join(lines)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--first-seed", type=int, default=0)
    ap.add_argument("--minutes", type=float, default=20.0)
    ap.add_argument("--factor", type=float, default=1.5)
    ap.add_argument("--extra-factors", default="", help="e.g. 0.6667,3 (posterior only)")
    ap.add_argument("--looseness", type=float, default=3.0)
    ap.add_argument("--no-cli", action="store_true", help="skip the term-selection path")
    ap.add_argument("--out", default=None, help="also write the raw rows as JSON")
    ap.add_argument("--rows", default=None, help="only summarize rows stored by --out")
    args = ap.parse_args()
    if args.rows:
        with open(args.rows) as f:
            rows = json.load(f)
        print(summarize(rows))
        return
    n = int(round(args.minutes * 60 * FS))
    factors = [args.factor] + [float(f) for f in args.extra_factors.split(",") if f]
    rows, t0 = [], time.perf_counter()
    for seed in range(args.first_seed, args.first_seed + args.seeds):
        rows.append(one(seed, n, factors, args.looseness, not args.no_cli))
        if args.out:
            with open(args.out, "w") as f:
                json.dump(rows, f)
        print(f"seed {seed}: {time.perf_counter() - t0:.0f} s", flush=True)
    print(f"\nmix A, {args.minutes:g} min at {FS:g} Hz ({n} samples), {len(rows)} seeds, "
          f"sheet = truth x {factors}, looseness {args.looseness:g}; width = median "
          "(high - low) / truth of the 90 % interval\n")
    cli = [k for k in rows[0] if k.startswith("cli/")]
    if cli:
        kept = {m: {p: sum(p in r[m]["present"] for r in rows) for p in PARAMS} for m in cli}
        print("terms kept by selection: " + "; ".join(
            f"{m}: " + ", ".join(f"{p} {c}/{len(rows)}" for p, c in kept[m].items())
            for m in cli) + "\n")
    print(summarize(rows))
    print(f"\n{len(rows)} records in {time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
