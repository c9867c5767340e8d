"""Overlapping Allan deviation: fogbayes against allantools in the same run.

fogbayes has two paths to the same estimator, both timed: ``allan_deviation``'s CPU default
for oadev (the cache-blocked NumPy accumulators of ``fogbayes.stats.allan_blocked``: the
Haar pyramid on octave grids) and the jitted XLA kernels (``allan_kernels``, the path on
accelerators and for the other kinds). The ratio column is allantools / the default path.

Cases (sizes shrink with ``--scale``):
  1. one record of 1e7 samples, octave taus;
  2. a batch of 64 sensors x 1e6 samples, octave taus (fogbayes: one vmapped call;
     allantools: a loop over sensors);
  3. one record of 1e7 samples, log-dense taus (20 per decade).

Each timing is the best of ``--repeat`` runs after one warm-up call (the warm-up, i.e. the
JIT compilation, is reported separately). The numbers are compared too: the largest relative
difference of the deviations must stay below 1e-9. Ratios, not seconds, are what carry over
between machines.

    python benchmarks/bench_allan.py            # full size
    python benchmarks/bench_allan.py --scale 0.1
"""

from __future__ import annotations

import argparse
import os
import platform
import time

import jax
import numpy as np

import fogbayes  # noqa: F401  (float64)
from _timing import best_of  # benchmarks/ is on sys.path when a script runs
from fogbayes.stats.allan_blocked import allan_variance_fast
from fogbayes.stats.allan_kernels import allan_variance
from fogbayes.stats.taus import cluster_sizes

allantools = __import__("allantools")


def ours_xla(Y, ms):
    return np.sqrt(np.asarray(jax.block_until_ready(allan_variance(Y, ms)[0])))


def ours(Y, ms):
    return np.sqrt(allan_variance_fast(Y, ms)[0])


def theirs(Y, ms, fs):
    taus = np.asarray(ms, float) / fs
    rows = np.atleast_2d(Y)
    out = np.stack([allantools.oadev(r, rate=fs, data_type="freq", taus=taus)[1] for r in rows])
    return out if Y.ndim == 2 else out[0]


def case(name: str, Y: np.ndarray, ms: tuple, fs: float, repeat: int) -> dict:
    t0 = time.perf_counter()
    ours_xla(Y, ms)
    compile_s = time.perf_counter() - t0
    t_xla = best_of(lambda: ours_xla(Y, ms), repeat)
    t_ours = best_of(lambda: ours(Y, ms), repeat)
    t_ref = best_of(lambda: theirs(Y, ms, fs), max(1, repeat - 1))
    ref = theirs(Y, ms, fs)
    diff = max(float(np.max(np.abs(f(Y, ms) / ref - 1))) for f in (ours, ours_xla))
    samples = Y.size
    print(f"| {name} | {len(ms)} | {t_ref:.3f} | {t_ours:.3f} | {t_ref / t_ours:.1f}x | "
          f"{t_xla:.3f} | {t_ref / t_xla:.1f}x | {samples / t_ours / 1e6:.0f} | "
          f"{compile_s:.1f} | {diff:.1e} |", flush=True)
    return {"case": name, "ratio": t_ref / t_ours, "ratio_xla": t_ref / t_xla,
            "max_rel_diff": diff}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--scale", type=float, default=1.0, help="fraction of the full sizes")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--sensors", type=int, default=64)
    args = ap.parse_args()
    rng = np.random.default_rng(0)
    fs = 100.0
    n_long = int(1e7 * args.scale)
    n_batch = int(1e6 * args.scale)
    print(f"{platform.processor() or platform.machine()}, jax {jax.__version__} "
          f"({jax.default_backend()}), allantools {allantools.__version__}\n")
    print(f"load average {os.getloadavg()[0]:.1f}\n")
    print("| case | taus | allantools s | fogbayes s | ratio | XLA kernels s | ratio | "
          "Msamples/s | XLA compile s | max rel diff |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    y = 400.0 + rng.normal(size=n_long) + 0.01 * np.cumsum(rng.normal(size=n_long))
    results = [case(f"1 x {n_long:.0e}, octave", y, cluster_sizes(n_long, "octave"), fs,
                    args.repeat)]
    Y = 400.0 + rng.normal(size=(args.sensors, n_batch))
    results.append(case(f"{args.sensors} x {n_batch:.0e}, octave", Y,
                        cluster_sizes(n_batch, "octave"), fs, args.repeat))
    results.append(case(f"1 x {n_long:.0e}, dense 20/decade", y,
                        cluster_sizes(n_long, "dense", per_decade=20), fs, args.repeat))
    worst = max(r["max_rel_diff"] for r in results)
    print(f"\nlargest relative difference to allantools: {worst:.1e} (must be < 1e-9)")
    if worst >= 1e-9:
        raise SystemExit(1)


if __name__ == "__main__":
    main()
