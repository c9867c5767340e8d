"""Would a plan averaged over the pilot's uncertainty reach K +-10 % more often?

    python benchmarks/plan_average_width.py B 0 2      # mix, first seed, last seed + 1

For each 1 h pilot of ``bench_plan.py`` (mix A or B) whose plan for K +-10 % (90 %) is not
refused: 64 draws from the pilot's joint log-normal (its GLS estimate and log covariance,
dispersion included), and the shortest length at which the *mean* (and, second, the median)
of the draws' predicted K half-widths reaches 10 % -- the average-length criterion of
Bayesian sample-size planning. Printed per pilot: the point plan's and these plans' lengths
(samples) and the width the true noise gives at each (``predicted_width`` at the truth).
Results: benchmarks/RESULTS_plan.md, section 4.
"""
import json
import os
import sys
import time

import numpy as np
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bench_plan as bp  # noqa: E402
from fogbayes.plan import plan_from_pilot, PlanError, predicted_width
from fogbayes.plan.length import (half_width, log_cov, predicted_se, se_for_width,
                                  search_length, shortest_record)
from fogbayes.allan.model import AllanParams, TERMS
from fogbayes.allan.data import prepare
from fogbayes.allan.fit import fit_range


def main():
    mix = sys.argv[1]
    seeds = range(int(sys.argv[2]), int(sys.argv[3]))
    truth = AllanParams(**bp.MIXES[mix][1])
    D = 64
    for seed in seeds:
        y, fs = bp.pilot(mix, seed)
        try:
            pp = plan_from_pilot(y, fs, "K", 0.10, level=0.9)
        except PlanError:
            continue
        t0 = time.time()
        fit, model = pp.fit, pp.terms
        data, _, _ = fit_range(prepare(y, fs), TERMS)  # the octaves the pilot fit kept
        cov = log_cov(fit.params, data, model)[1] * fit.info["dispersion"]
        p = np.array(fit.params, float)
        on = np.array([t in model for t in TERMS])
        rng = np.random.default_rng(seed)
        L = np.linalg.cholesky(cov + 1e-15 * np.eye(cov.shape[0]))
        th = np.log(p[on])[None] + rng.standard_normal((D, on.sum())) @ L.T
        draws = [np.where(on, 0.0, p) for _ in range(D)]
        for q, t in zip(draws, th):
            q[on] = np.exp(t)
        def mean_w(n, how):
            w = np.array([half_width(predicted_se(q, fs, n, model, tau_min=pp.tau_min)["K"], 0.9) for q in draws])
            return float(np.mean(w) if how == "mean" else np.median(w))
        out = {"seed": seed, "point_n": pp.plan.n,
               "point_w_truth": predicted_width(truth, fs, pp.plan.n, "K", level=0.9, terms=("Q","N","B","K"))}
        n_lo, n_max = shortest_record(fs, model, pp.tau_min), int(30 * 86400 * fs)
        for how in ("mean", "median"):
            n, _ = search_length(lambda k: se_for_width(mean_w(k, how), 0.9), se_for_width(0.10, 0.9), n_lo, n_max)
            out[how + "_n"] = n
            out[how + "_w_truth"] = None if n is None else predicted_width(truth, fs, n, "K", level=0.9, terms=("Q","N","B","K"))
        out["s"] = time.time() - t0
        print(json.dumps(out), flush=True)


if __name__ == "__main__":
    main()
