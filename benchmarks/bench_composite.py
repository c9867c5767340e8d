"""Composite model (paper 000): compensation throughput and the statistical studies.

    python benchmarks/bench_composite.py speed    [--n 4000000] [--repeat 5]
    python benchmarks/bench_composite.py coverage [--seeds 60]  [--bayes 0]
    python benchmarks/bench_composite.py orders   [--seeds 40]

speed: one run, best of ``--repeat`` after a warm-up (compilation reported apart), n
  samples on paper 000's grid range (T in -30..60 deg C, W in -80..80 deg/s, t in 0..60 s):
  * the jitted compensator (Halley, the iteration count it picks: 2; Newton), float64 and
    float32, called two ways: allocating (returns rate and flag: reads U, T, t, writes
    8 + 1 bytes: 33 bytes per float64 sample) and streaming (``Compensator.stream``: the
    rate is written into U's donated buffer: 32 bytes per sample);
  * the paper's 2-iteration fixed point, jitted the same ways (the baseline the exact
    inversion must not be slower than);
  * the same Halley algorithm in plain NumPy (compensate_numpy);
  * memory copies of the same bytes: ``np.copyto`` into an existing buffer (memcpy speed,
    the yardstick of the streaming path) and ``src.copy()`` (allocating, the yardstick of
    the allocating path: first writes to fresh pages cost page faults, for any library).
  Also 64 sensors through one jit(vmap(...)) call (coefficients as arguments).
coverage: 90 % intervals of the 18 raw coefficients against the truth over seeds (the
  default paper000 noise: white + bias instability), for joint GLS (cell-offset noise),
  joint OLS (white), classification fitting, and (``--bayes k``) k NUTS posteriors.
orders: how often the LOO / WAIC / sigma_d order selections give back (2, 3, 2, 2).
Ratios, not seconds, carry over between machines (this one: 2 shared cores).
"""

from __future__ import annotations

import argparse
import json
import platform
import time
import warnings

import jax
import jax.numpy as jnp
import numpy as np

import fogbayes  # noqa: F401  (float64)
from _timing import best_of  # benchmarks/ is on sys.path when a script runs
from fogbayes.composite.compensate import build_compensator, compensate_numpy, compensate_sensors
from fogbayes.composite.model import PAPER_000, PAPER_ORDERS, Scaling, from_raw, raw_predict


def _stream_time(comp, U, T, t, repeat: int) -> float:
    """Best time of comp.stream over fresh donated copies of U (one per call)."""
    Td, td = jax.device_put(T), jax.device_put(t)
    bufs = [jax.device_put(U.copy()) for _ in range(repeat + 1)]
    jax.block_until_ready(comp.stream(bufs.pop(), Td, td))  # compile
    times = []
    for b in bufs:
        jax.block_until_ready(b)
        t0 = time.perf_counter()
        jax.block_until_ready(comp.stream(b, Td, td))
        times.append(time.perf_counter() - t0)
    return min(times)


def speed(n: int, repeat: int, sensors: int) -> dict:
    rng = np.random.default_rng(0)
    T = rng.uniform(-30, 60, n)
    W = rng.uniform(-80, 80, n)
    t = rng.uniform(0, 60, n)
    U = raw_predict(PAPER_000, T, W, t)
    sc = Scaling(15.0, 45.0, 80.0, 60.0, float(U.mean()), float(np.abs(U - U.mean()).max()))
    p = from_raw(PAPER_000, sc)
    out = {"machine": platform.processor() or platform.machine(), "jax": jax.__version__,
           "backend": jax.default_backend(), "n": n}
    res = {}
    # the copies: into an existing buffer (memcpy speed) and allocating a new one (what an
    # array-returning function pays: fresh pages are faulted in on first write)
    src = np.ones(n * 2)  # 16 n bytes: a copy moves 32 n, like the compensator's stream
    dst = np.zeros_like(src)
    res["copy_into"] = {"GB_s": 2 * src.nbytes / best_of(lambda: np.copyto(dst, src), repeat) / 1e9}
    res["copy_alloc"] = {"GB_s": 2 * src.nbytes / best_of(lambda: src.copy(), repeat) / 1e9}
    for label, method, dtype in (("halley_f64", "halley", np.float64),
                                 ("paper_f64", "paper", np.float64),
                                 ("newton_f64", "newton", np.float64),
                                 ("halley_f32", "halley", np.float32),
                                 ("paper_f32", "paper", np.float32)):
        comp = build_compensator(p, sc, T_range=(-30, 60), W_range=(-80, 80), method=method)
        arrs = [a.astype(dtype) for a in (U, T, t)]
        args = [jax.device_put(a) for a in arrs]
        t0 = time.perf_counter()
        jax.block_until_ready(comp(*args))
        compile_s = time.perf_counter() - t0
        sec = best_of(lambda c=comp, a=args: jax.block_until_ready(c(*a)), repeat)
        isz = np.dtype(dtype).itemsize
        rate = np.asarray(comp(*args).rate, float)
        err = np.abs(rate - W) / np.abs(W)
        sec_s = _stream_time(comp, *arrs, repeat)
        res[label] = {
            "iterations": comp.iterations, "compile_s": round(compile_s, 2),
            # allocating call: reads U, T, t; writes rate and the in-range flag
            "Msamples_s": n / sec / 1e6, "GB_s": (4 * isz + 1) * n / sec / 1e9,
            # streaming: reads U, T, t; writes rate into U's buffer
            "stream_Msamples_s": n / sec_s / 1e6, "stream_GB_s": 4 * isz * n / sec_s / 1e9,
            "max_rel_err_pct": float(np.nanmax(err[np.abs(W) > 0.5]) * 100)}
        res[label]["vs_copy_alloc"] = res[label]["GB_s"] / res["copy_alloc"]["GB_s"]
        res[label]["stream_vs_copy_into"] = res[label]["stream_GB_s"] / res["copy_into"]["GB_s"]
    comp = build_compensator(p, sc, T_range=(-30, 60), W_range=(-80, 80))
    m = min(n, 2_000_000)  # plain NumPy: its temporaries make it slow; rate per sample holds
    sec = best_of(lambda: compensate_numpy(p, sc, comp.box, U[:m], T[:m], t[:m],
                                           iterations=comp.iterations), max(1, repeat // 2))
    res["numpy_f64"] = {"Msamples_s": m / sec / 1e6, "GB_s": 33 * m / sec / 1e9}
    res["numpy_f64"]["vs_copy_alloc"] = res["numpy_f64"]["GB_s"] / res["copy_alloc"]["GB_s"]
    res["halley_over_paper_time"] = res["paper_f64"]["Msamples_s"] / res["halley_f64"]["Msamples_s"]
    res["halley_over_paper_time_stream"] = (res["paper_f64"]["stream_Msamples_s"]
                                            / res["halley_f64"]["stream_Msamples_s"])
    res["jax_over_numpy_speedup"] = res["halley_f64"]["Msamples_s"] / res["numpy_f64"]["Msamples_s"]
    # many sensors: one jit(vmap) call over k sensors with their own coefficients
    k = sensors
    ns = max(n // k, 1000)
    stack = jax.tree_util.tree_map(lambda a: jnp.stack([a * (1 + 1e-4 * i) for i in range(k)]), p)
    scs = Scaling(*[jnp.full(k, v) for v in sc])
    box = jnp.tile(jnp.asarray(comp.box), (k, 1))
    Us, Ts, ts = (jnp.tile(jnp.asarray(a[:ns]), (k, 1)) for a in (U, T, t))
    f = lambda: jax.block_until_ready(compensate_sensors(stack, scs, box, Us, Ts, ts))  # noqa: E731
    f()
    sec = best_of(f, repeat)
    res["sensors_vmap"] = {"k": k, "n_each": ns, "Msamples_s": k * ns / sec / 1e6,
                           "GB_s": 33 * k * ns / sec / 1e9}
    out["results"] = res
    return out


def _sim_data(seed: int):
    from fogbayes.composite.cells import rate_data
    from fogbayes.simulate.scenarios import simulate

    return rate_data(simulate("paper000", seed=seed).recording)[0]


def coverage(seeds: int, bayes: int) -> dict:
    from scipy import stats

    from fogbayes.composite.classify import classify_fit
    from fogbayes.composite.fit import fit_joint
    from fogbayes.composite.model import pack, raw_map, raw_offset

    truth = np.concatenate([PAPER_000.M.ravel(), PAPER_000.c, PAPER_000.d])
    q = stats.norm.ppf(0.95)
    qc = np.r_[np.full(15, q), np.full(3, stats.t.ppf(0.95, 7))]
    hits = {"joint_cells": [], "joint_white": [], "classification": [], "bayes_cells": []}
    diag = []
    for seed in range(seeds):
        d = _sim_data(1000 + seed)
        for key, fit, qq in (("joint_cells", fit_joint(d, PAPER_ORDERS, noise="cells"), q),
                             ("joint_white", fit_joint(d, PAPER_ORDERS, noise="white"), q),
                             ("classification", classify_fit(d, orders=PAPER_ORDERS), qc)):
            J = raw_map(PAPER_ORDERS, fit.scaling)
            est = J @ np.asarray(pack(fit.params)) + raw_offset(PAPER_ORDERS, fit.scaling)
            sd = np.sqrt(np.diag(J @ fit.cov @ J.T))
            hits[key].append(np.abs(est - truth) < qq * sd)
        if seed < bayes:
            from fogbayes.composite.bayes import fit_bayes

            bf = fit_bayes(d, PAPER_ORDERS, seed=seed, noise="cells")
            lo, hi = np.quantile(bf.raw_draws().reshape(-1, 18), [0.05, 0.95], axis=0)
            hits["bayes_cells"].append((lo < truth) & (truth < hi))
            diag.append({"rhat_max": bf.rhat_max, "ess_min": bf.ess_min,
                         "divergences": bf.divergences, "converged": bf.converged})
            print(seed, diag[-1], flush=True)
        print(seed, {k: round(float(np.mean(v)), 3) for k, v in hits.items() if v}, flush=True)
    out = {k: {"coverage": float(np.mean(v)), "runs": len(v),
               "per_coefficient": np.mean(v, axis=0).round(2).tolist()}
           for k, v in hits.items() if v}
    if diag:
        out["bayes_cells"]["diagnostics"] = diag
    return out


def orders(seeds: int) -> dict:
    from fogbayes.composite.compare import select_orders

    out = {}
    for crit in ("loo", "waic", "sigma_d"):
        got = []
        for seed in range(seeds):
            got.append(select_orders(_sim_data(2000 + seed), criterion=crit).orders.label())
        out[crit] = {"recovered": float(np.mean([g == PAPER_ORDERS.label() for g in got])),
                     "runs": seeds, "chosen": {g: got.count(g) for g in sorted(set(got))}}
        print(crit, out[crit], flush=True)
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("what", choices=("speed", "coverage", "orders"))
    ap.add_argument("--n", type=int, default=4_000_000)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--sensors", type=int, default=64)
    ap.add_argument("--seeds", type=int, default=60)
    ap.add_argument("--bayes", type=int, default=0)
    args = ap.parse_args()
    warnings.filterwarnings("ignore")
    if args.what == "speed":
        res = speed(args.n, args.repeat, args.sensors)
    elif args.what == "coverage":
        res = coverage(args.seeds, args.bayes)
    else:
        res = orders(args.seeds)
    print(json.dumps(res, indent=1))


if __name__ == "__main__":
    main()
