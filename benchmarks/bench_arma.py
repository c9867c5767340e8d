"""Benchmark: many ARMA fits in one vmapped call vs a statsmodels loop; order-selection study.

Usage (full size of the issue; minutes on a 2-core machine)::

    python benchmarks/bench_arma.py speed --series 400 --n 10000
    python benchmarks/bench_arma.py select --n 1000 --seeds 100

``speed`` simulates ARMA(2,1) series (paper sign: phi = (0.5, -0.4), theta = -0.5), fits
them all with ``fit_arma_batch`` (one jit-compiled, vmapped call; timed cold = with
compilation, and warm) and with a loop of statsmodels ``ARIMA(order=(2,0,1), trend="n").fit()``
over the same series, and reports the time ratio and how far the estimates are apart in
statsmodels' standard errors (and which log-likelihood is higher). ``select`` reports how
often AIC and BIC pick the true order among paper 002's candidates.
Ratios are measured in the same run (absolute times drift with machine load).
"""

from __future__ import annotations

import argparse
import json
import time
import warnings
from collections import Counter

import numpy as np

TRUTH = {
    (1, 0): ([0.6], []),
    (2, 0): ([0.5, -0.35], []),
    (3, 0): ([0.4, -0.3, 0.3], []),
    (1, 1): ([0.6], [-0.5]),
    (2, 1): ([0.5, -0.4], [-0.5]),
}


def simulate(phi, theta, n: int, seeds) -> np.ndarray:
    from statsmodels.tsa.arima_process import arma_generate_sample

    return np.stack([arma_generate_sample(np.r_[1, -np.asarray(phi)], np.r_[1, -np.asarray(theta)],
                                          n, distrvs=np.random.default_rng(s).standard_normal,
                                          burnin=300) for s in seeds])


def speed(series: int, n: int, sm_series: int | None) -> dict:
    import jax
    from statsmodels.tsa.arima.model import ARIMA

    from fogbayes.arma.fit import fit_arma_batch

    phi, theta = TRUTH[(2, 1)]
    X = simulate(phi, theta, n, range(series))
    t0 = time.perf_counter()
    fits = jax.block_until_ready(fit_arma_batch(X, p=2, q=1))
    cold = time.perf_counter() - t0
    t0 = time.perf_counter()
    fits = jax.block_until_ready(fit_arma_batch(X, p=2, q=1))
    warm = time.perf_counter() - t0

    m = series if sm_series is None else min(sm_series, series)
    est, se, llf = [], [], []
    t0 = time.perf_counter()
    for i in range(m):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            r = ARIMA(X[i], order=(2, 0, 1), trend="n").fit()
        est.append(np.r_[r.params[:2], -r.params[2], r.params[3]])
        se.append(r.bse)
        llf.append(r.llf)
    sm_time = time.perf_counter() - t0
    est, se, llf = np.array(est), np.array(se), np.array(llf)
    ours = np.c_[np.asarray(fits.phi), np.asarray(fits.theta), np.asarray(fits.sigma2)][:m]
    z = np.abs(ours - est) / se
    dll = np.asarray(fits.loglik)[:m] - llf
    per_sm = sm_time / m
    return {
        "series": series, "n": n, "statsmodels_series": m,
        "fogbayes_cold_s": cold, "fogbayes_warm_s": warm,
        "statsmodels_s": sm_time, "statsmodels_per_series_s": per_sm,
        "ratio_warm": per_sm * series / warm, "ratio_cold": per_sm * series / cold,
        "converged": float(np.mean(np.asarray(fits.converged))),
        "max_diff_in_se": float(z.max()), "median_diff_in_se": float(np.median(z)),
        "loglik_ours_minus_sm_min": float(dll.min()), "loglik_ours_minus_sm_max": float(dll.max()),
    }


def select(n: int, seeds: int) -> dict:
    import jax

    from fogbayes.arma.select import PAPER_CANDIDATES, order_name, select_order

    out = {}
    for order, (phi, theta) in TRUTH.items():
        X = simulate(phi, theta, n, [hash((order, s)) % 2**31 for s in range(seeds)])
        sel = select_order(X, PAPER_CANDIDATES)
        jax.block_until_ready(sel.aic)
        row = {}
        for crit in ("aic", "bic"):
            chosen = [sel.orders[i] for i in np.asarray(sel.best(crit))]
            row[crit] = float(np.mean([c == order for c in chosen]))
            row[crit + "_choices"] = {order_name(*k): v for k, v in Counter(chosen).items()}
        row["converged"] = float(np.mean(np.asarray(sel.fits.converged)))
        out[order_name(*order)] = row
    return {"n": n, "seeds": seeds, "rates": out}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="what", required=True)
    s = sub.add_parser("speed")
    s.add_argument("--series", type=int, default=400)
    s.add_argument("--n", type=int, default=10_000)
    s.add_argument("--sm-series", type=int, default=None,
                   help="fit only this many with statsmodels (reduced size; ratio per series)")
    c = sub.add_parser("select")
    c.add_argument("--n", type=int, default=1000)
    c.add_argument("--seeds", type=int, default=100)
    ap.add_argument("--json", default=None, help="also write the result as JSON")
    a = ap.parse_args()
    import fogbayes  # noqa: F401  (float64)

    res = speed(a.series, a.n, a.sm_series) if a.what == "speed" else select(a.n, a.seeds)
    print(json.dumps(res, indent=2))
    if a.json:
        with open(a.json, "w") as f:
            json.dump(res, f, indent=2)


if __name__ == "__main__":
    main()
