"""Total deviations (TOTDEV, MTOTDEV, Theo1): fogbayes end to end against allantools.

fogbayes is timed as users call it: ``allan_deviation(y, fs, kind=...)`` with octave taus,
noise identification, EDF and chi-square intervals; allantools' ``totdev``/``mtotdev``/
``theo1`` (``data_type="freq"``) return deviations only, on the same averaging factors.
allantools' MTOTDEV and Theo1 are O(N m) Python loops per tau, so they run on short records
(``--scale`` shrinks every size); fogbayes-only rows show longer records.

The first fogbayes call of each kind runs with an empty Numba cache (a temporary folder,
unless ``--keep-cache``), so "first call" is compilation plus one run; later rows are warm
(best of ``--repeat``). Ratios, not seconds, carry over between machines. The deviations
are compared too: the largest relative difference must stay below 1e-9.

    python benchmarks/bench_total.py
    python benchmarks/bench_total.py --scale 0.5 --repeat 3
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import tempfile
import time

if "--keep-cache" not in sys.argv:  # before fogbayes is imported: its Numba cache folder
    os.environ["FOGBAYES_CACHE_DIR"] = tempfile.mkdtemp(prefix="fogbayes-bench-total-")

import numpy as np
from _timing import best_of  # benchmarks/ is on sys.path when a script runs

import fogbayes  # noqa: F401  (float64)
from fogbayes.stats.allan import allan_deviation

allantools = __import__("allantools")

# (kind, samples, compare with allantools)
CASES = [("totdev", 10_000, True), ("totdev", 100_000, True), ("totdev", 1_000_000, True),
         ("mtotdev", 1_000, True), ("mtotdev", 2_000, True), ("mtotdev", 10_000, False),
         ("theo1", 1_000, True), ("theo1", 4_000, True), ("theo1", 100_000, False)]


def ours(kind, y, fs):
    return allan_deviation(y, fs, kind=kind, taus="octave", ci=0.683)


def theirs(kind, y, fs, ms):
    return getattr(allantools, kind)(y, rate=fs, data_type="freq", taus=np.asarray(ms) / fs)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--scale", type=float, default=1.0, help="fraction of the sizes")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--keep-cache", action="store_true",
                    help="use the user's Numba cache (first call = cache load, not compile)")
    args = ap.parse_args()
    rng = np.random.default_rng(0)
    fs = 10.0
    print(f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
          f"allantools {allantools.__version__}, numba cache "
          f"{'user' if args.keep_cache else 'empty (first call compiles)'}, "
          f"load average {os.getloadavg()[0]:.1f}\n")
    print("| kind | samples | taus | fogbayes first call s | fogbayes warm s | allantools s | "
          "allantools / fogbayes | max rel diff |")
    print("|---|---|---|---|---|---|---|---|")
    seen, worst = set(), 0.0
    for kind, n, compare in CASES:
        n = max(64, int(n * args.scale))
        # white + flicker-like + random-walk rate noise on an offset (gyro-like)
        y = 5.0 + rng.normal(size=n) + 0.003 * np.cumsum(rng.normal(size=n))
        t0 = time.perf_counter()
        res = ours(kind, y, fs)
        first = time.perf_counter() - t0
        first_s = f"{first:.3f}" if kind not in seen else "(warm)"
        seen.add(kind)
        warm = best_of(lambda kind=kind, y=y: ours(kind, y, fs), args.repeat)
        if compare:
            slow = n > 1500 and kind != "totdev"  # allantools' Python loops: once
            t_ref = best_of(lambda kind=kind, y=y, ms=res.m: theirs(kind, y, fs, ms),
                            1 if slow else args.repeat)
            ref = theirs(kind, y, fs, res.m)
            diff = float(np.max(np.abs(res.dev / ref[1] - 1)))
            worst = max(worst, diff)
            r = t_ref / warm
            ref_s, diff_s = f"{t_ref:.3f}", f"{diff:.1e}"
            ratio = f"{r:.1f}x" if r < 10 else f"{r:.0f}x"
        else:
            ref_s, ratio, diff_s = "-", "-", "-"
        print(f"| {kind} | {n:.0e} | {len(res.m)} | {first_s} | {warm:.4f} | {ref_s} | {ratio} | "
              f"{diff_s} |", flush=True)
    print(f"\nlargest relative difference to allantools: {worst:.1e} (must be < 1e-9)")
    if worst >= 1e-9:
        raise SystemExit(1)


if __name__ == "__main__":
    main()
