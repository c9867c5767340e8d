"""Coverage of the Allan noise fits on simulated records with known Q, N, B, K.

For each noise mix and record length, simulate many records with
:func:`fogbayes.simulate.noise.allan_noise`, fit them (GLS and/or the NumPyro posterior) and
count how often the 90 % interval of each parameter contains the truth; compare the RMS
relative error of the fitted values with that of the IEEE-952 slope readouts.

The records are cut from 4 x longer draws (``flicker_span=1``: the cut is made here), so
the flicker reaches below 1/T, as a real sensor's does (see RESULTS_allan.md).

    python benchmarks/coverage_allan.py --methods wls --seeds 200
    python benchmarks/coverage_allan.py --methods bayes --seeds 40 --out cov.json
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

import fogbayes  # noqa: F401  (float64)
from fogbayes.allan.data import prepare
from fogbayes.allan.fit import fit_wls
from fogbayes.allan.readout import slope_readouts
from fogbayes.simulate.noise import allan_noise
from fogbayes.stats.allan import allan_deviation

PARAMS = ("Q", "N", "B", "K")
#: name -> (fs Hz, truth). Mix A: a tactical FOG at 10 Hz with the Q/N, N/B and B/K
#: crossovers at 0.3, 30 and 300 s; mix B: a MEMS-like sensor at 100 Hz with crossovers at
#: 0.05, 20 and 150 s. Record lengths are chosen so that every term shows in the curve.
MIXES = {
    "A": (10.0, dict(Q=0.19, N=0.01, B=0.165, K=0.66)),
    "B": (100.0, dict(Q=0.775, N=0.1, B=2.02, K=11.4)),
}
#: log2 record lengths per mix: A 3.6 h and 14.6 h at 10 Hz, B 44 min and 2.9 h at 100 Hz
LENGTHS = {"A": (17, 19), "B": (18, 20)}


def simulate(mix: str, n: int, seed: int) -> tuple[np.ndarray, float, dict]:
    fs, truth = MIXES[mix]
    return allan_noise(4 * n, fs, seed=seed, flicker_span=1, **truth)[:n], fs, truth


#: sampler sizes passed to the posterior (empty: the library's defaults); --warmup, --draws
SAMPLER: dict = {}
#: select_terms' own options (--trial-warmup)
SELECT: dict = {}


def one(mix: str, n: int, seed: int, methods: tuple[str, ...]) -> dict:
    y, fs, truth = simulate(mix, n, seed)
    data = prepare(y, fs)
    out = {"mix": mix, "n": n, "seed": seed}
    dev = allan_deviation(y, fs, taus="octave", ci=0.9)
    out["adev"] = {"tau": dev.tau.tolist(), "dev": dev.dev.tolist(),
                   "low": dev.dev_low.tolist(), "high": dev.dev_high.tolist()}
    for method in methods:
        t0 = time.perf_counter()
        from fogbayes.allan import bayes as ab

        if method in ("wls", "wls4"):
            fit = fit_wls(data, PARAMS if method == "wls4" else ab.TERMS)
        elif method in ("bayes", "bayes4"):
            fit = ab.fit_bayes(data, PARAMS if method == "bayes4" else ab.TERMS, seed=seed,
                               **SAMPLER).fit
        elif method == "ssm":  # K only: the time-domain likelihood study (k_timedomain.py)
            from k_timedomain import fit_walk

            e = fit_walk(y, fs)
            out[method] = {"K": [e.value, e.low, e.high]}
            out[method + "_converged"] = e.converged
            out[method + "_seconds"] = time.perf_counter() - t0
            continue
        elif method == "select":
            sel = ab.select_terms(data, seed=seed, **SAMPLER, **SELECT)
            rep = ab.reported_terms(sel)
            out["select_present"] = list(sel.present)
            fit = sel.selected.fit._replace(terms={t: e for t, (e, _) in rep.items()})
        out[method] = {p: list(fit.terms[p][:3]) for p in PARAMS}
        out[method + "_converged"] = fit.converged
        out[method + "_seconds"] = time.perf_counter() - t0
    return out


def readouts(row: dict) -> dict:
    """IEEE-952 slope readouts of the row's octave ADEV (recomputed, so rows stay raw)."""
    a = row["adev"]
    ro = slope_readouts(a["tau"], a["dev"], a["low"], a["high"])
    return {p: (None if ro[p] is None else ro[p].value) for p in PARAMS}


def table(rows: list[dict], methods) -> str:
    lines = ["| mix | n | method | " + " | ".join(f"cover {p}" for p in PARAMS)
             + " | " + " | ".join(f"RMS {p} fit / readout" for p in PARAMS) + " |",
             "|---|---|---|" + "---|" * (2 * len(PARAMS))]
    keys = sorted({(r["mix"], r["n"]) for r in rows})
    for r in rows:
        r["readout"] = readouts(r)
    for mix, n in keys:
        sel = [r for r in rows if r["mix"] == mix and r["n"] == n]
        truth = MIXES[mix][1]
        for m in methods:
            cov, rms = [], []
            for p in PARAMS:
                if p not in sel[0][m]:  # a method that estimates some terms only
                    cov.append("-")
                    rms.append("-")
                    continue
                inside = [r[m][p][1] <= truth[p] <= r[m][p][2] for r in sel]
                cov.append(f"{np.mean(inside):.0%} ({len(inside)})")
                fe = np.array([r[m][p][0] / truth[p] - 1 for r in sel])
                re = np.array([r["readout"][p] / truth[p] - 1 for r in sel
                               if r["readout"][p] is not None])
                nr = len(re)
                rr = np.sqrt(np.mean(re**2)) if nr else float("nan")
                rms.append(f"{np.sqrt(np.mean(fe**2)):.3f} / {rr:.3f}"
                           + ("" if nr == len(sel) else f" ({nr} read)"))
            conv = np.mean([r[m + "_converged"] for r in sel])
            sec = np.mean([r[m + "_seconds"] for r in sel])
            lines.append(f"| {mix} | 2^{int(np.log2(n))} | {m} (conv {conv:.0%}, {sec:.1f} s) | "
                         + " | ".join(cov) + " | " + " | ".join(rms) + " |")
    return "\n".join(lines)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--methods", default="wls")
    ap.add_argument("--seeds", type=int, default=100)
    ap.add_argument("--first-seed", type=int, default=0)
    ap.add_argument("--mixes", default="A,B")
    ap.add_argument("--lengths", default=None, help="log2 record lengths (default: per mix)")
    ap.add_argument("--out", default=None, help="also write the raw rows as JSON")
    ap.add_argument("--warmup", type=int, default=None, help="posterior warm-up steps")
    ap.add_argument("--draws", type=int, default=None, help="posterior draws per chain")
    ap.add_argument("--trial-warmup", type=int, default=None,
                    help="warm-up steps of select's drop-one models (step size only, from "
                         "the current model's adaptation)")
    args = ap.parse_args()
    if args.trial_warmup is not None:
        SELECT["trial_warmup"] = args.trial_warmup
    if args.warmup is not None:
        SAMPLER["num_warmup"] = args.warmup
    if args.draws is not None:
        SAMPLER["num_samples"] = args.draws
    methods = tuple(args.methods.split(","))
    rows = []
    t0 = time.perf_counter()
    for mix in args.mixes.split(","):
        lengths = args.lengths.split(",") if args.lengths else LENGTHS[mix]
        for k in lengths:
            for seed in range(args.first_seed, args.first_seed + args.seeds):
                rows.append(one(mix, 2 ** int(k), seed, methods))
            if args.out:
                with open(args.out, "w") as f:
                    json.dump(rows, f)
    print(table(rows, methods))
    print(f"\n{len(rows)} records in {time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
