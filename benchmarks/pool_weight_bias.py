"""Why the pooled population B sits above the fleet: precision weights that follow the error.

    python benchmarks/pool_weight_bias.py [--reps 20]

The fleets of ``bench_pool.py`` (same seeds; 20 units of 3.6 h at 10 Hz, B spread 0.3 in
log). Every unit is fitted alone (GLS, five terms). Per fleet, three estimates of the fleet's
mean log B are compared with the mean of its units' *true* log B (so the draw of the fleet
itself is taken out):

* the plain mean of the units' log B estimates;
* the random-effects mean, weights ``1 / (s^2 + v_u)`` with the true spread s = 0.3 and
  each unit's log-space variance ``v_u`` (:func:`fogbayes.pool.allan.resolved_covariance`),
  as the pool's hierarchical model weights them;
* the median of the units' estimates.

Printed: the mean over fleets of each estimate minus the realised mean (with its standard
error), the single units' mean log error, and the correlation between a unit's error and
its weight.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import bench_pool as bp  # noqa: E402  (the fleets, the same seeds)
from fogbayes.pool.allan import resolved_covariance  # noqa: E402

B = 2  # index of B in the five terms Q, N, B, K, R


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--reps", type=int, default=20)
    args = ap.parse_args()
    s2 = bp.SPREAD["B"] ** 2
    per_fleet, errors, weights = [], [], []
    for rep in range(args.reps):
        rng = np.random.default_rng(10_000 + rep)
        truths = [bp.unit_truth(rng) for _ in range(20)]
        fits = [bp.fit_record(bp.simulate(tr, 2 ** 17, seed=100_000 * rep + u), f"u{u}")
                for u, tr in enumerate(truths)]
        true_log = np.log([tr["B"] for tr in truths])
        y = np.array([f.logp[B] for f in fits])
        v = np.array([resolved_covariance(f)[B, B] for f in fits])
        w = 1.0 / (s2 + v)
        realised = true_log.mean()
        per_fleet.append((y.mean() - realised, np.sum(w * y) / np.sum(w) - realised,
                          np.median(y) - realised))
        errors.extend(y - true_log)
        weights.extend(w / w.mean())
    d = np.array(per_fleet)
    se = d.std(axis=0, ddof=1) / np.sqrt(len(d))
    for j, name in enumerate(("plain mean", "random-effects weighted mean", "median")):
        print(f"{name:30s} - realised mean log B: {d[:, j].mean():+.4f} (se {se[j]:.4f})")
    e, w = np.array(errors), np.array(weights)
    print(f"single units: mean log error of B {e.mean():+.4f} (se {e.std(ddof=1) / np.sqrt(e.size):.4f}), "
          f"{e.size} units; corr(error, weight) {np.corrcoef(e, w)[0, 1]:+.3f}; "
          f"weights (relative) {w.min():.2f} .. {w.max():.2f}")


if __name__ == "__main__":
    main()
