"""NUTS wall time and effective samples per second of every NumPyro posterior in fogbayes.

    python benchmarks/bench_nuts.py                       # API default sizes, all models
    python benchmarks/bench_nuts.py --quick               # tiny sizes (smoke run, ~2 min on 2 cores)
    python benchmarks/bench_nuts.py --models arma allan   # a subset
    python benchmarks/bench_nuts.py --chains 4 --warmup 500 --samples 500 --json out.json

Models (one row each; data as in the tests, fixed seeds):
  composite  ``composite.bayes.fit_bayes``, cells noise, PAPER_ORDERS, on the
             paper000 scenario (seed 11, 20 s dwell, 5 s smoothing); NUTS samples the noise
             parameters (u_sigma, log_lam, rho), theta is drawn exactly given them.
  allan      ``allan.bayes.fit_bayes``, all five terms, on 2^14 samples at 10 Hz
             of ``allan_noise`` (Q, N, B, K; seed 21); NUTS samples log Q .. log R (dense
             mass). ``discrepancy="auto"``: a refit with the discrepancy term, when the
             goodness-of-fit check asks for one, is inside the timed call ("+disc" after the
             model name).
  arma       ``arma.bayes.arma_posterior``, ARMA(1, 1) (phi 0.6, theta -0.4,
             n = 600, seed 0); NUTS samples pacf_phi, pacf_theta, sigma.
  thermal    ``workflow.thermal.fit_recording(model="thermal", bayes=True)`` on the 1 h, 1 Hz
             "thermal" scenario (seed 1): least squares + ``inference.bayes`` NUTS (AR(1)
             noise, 10 s blocks) + WAIC/LOO; NUTS samples beta, log sigma, the AR PACF.

Per model, in one process and in this order: a first call (seed 0: includes tracing and
XLA compilation), then a second call with another seed (seed 1: "warm", on the same data,
reusing whatever the API caches). Both are whole API calls, so they include the model's
own pre- and post-processing (start values, exact theta draws, ArviZ summaries, WAIC/LOO).
Compilations are recorded with ``jax.monitoring`` (XLA compile, tracing and lowering
events, with the function's name) during each call, so the table shows whether the warm
call compiled again; the functions it compiled are listed under the table (JSON: all of it).
Models run in the order given, so a later model's first call may find small shared
functions compiled already.

Columns:
  model        the posterior (above)
  chains x (warmup + draws)   sizes used (``--chains/--warmup/--samples`` override the
               API defaults; ``--quick`` uses 2 x (100 + 100))
  first s      wall time of the first call (includes compilation)
  warm s       wall time of the second call
  warm compile s (n)   seconds of XLA compilation inside the warm call and their number
               (many seconds: the API recompiles on every call; tracing and lowering,
               in the JSON, come on top)
  ess_bulk min (param) minimum rank-normalised bulk ESS (ArviZ) over the NUTS-sampled
               parameters of the warm call, and the parameter that has it (thermal:
               the document holds only the minimum over beta, sigma, phi)
  r_hat max    maximum rank-normalised split R-hat (ArviZ) over the same parameters
               (the JSON also keeps each API's own diagnostics, under "api": allan's are
               NumPyro's n_eff and R-hat, which differ from ArviZ's)
  div          divergent transitions after warm-up (warm call)
  ESS/s        ess_bulk min / warm s (effective draws of the worst parameter per second of a
               whole warm API call)
The JSON also has ESS per second of the warm call less its XLA compile time.
The load average (``os.getloadavg()``) is printed before and after; this machine has 2
shared cores, so repeat a surprising number before trusting it.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import time
import warnings

import jax
import numpy as np

import fogbayes  # float64 on (and __version__ below)

# --------------------------------------------------------------------- compile counting
_EVENTS: list[tuple[str, float, str]] = []
_TRACE, _LOWER, _XLA = ("/jax/core/compile/jaxpr_trace_duration",
                        "/jax/core/compile/jaxpr_to_mlir_module_duration",
                        "/jax/core/compile/backend_compile_duration")


def _listener(name, secs, *, fun_name="?", **_):
    if name in (_TRACE, _LOWER, _XLA):
        _EVENTS.append((name, secs, fun_name))


jax.monitoring.register_event_duration_secs_listener(_listener)


def _timed_call(fn):
    """(result, wall s, compile record) of one call; the record sums the XLA compilations
    (count, seconds, the longest ones by function name) and, apart, the tracing and lowering
    seconds (nested jits are traced inside their callers, so those sums overlap)."""
    _EVENTS.clear()
    t0 = time.perf_counter()
    out = fn()
    wall = time.perf_counter() - t0
    xla = sorted(((s, f) for n, s, f in _EVENTS if n == _XLA), reverse=True)
    rec = {"xla_compiles": len(xla), "xla_compile_s": sum(s for s, _ in xla),
           "trace_s": sum(s for n, s, _ in _EVENTS if n == _TRACE),
           "lower_s": sum(s for n, s, _ in _EVENTS if n == _LOWER),
           "longest": [[f, round(s, 2)] for s, f in xla[:5]]}
    return out, wall, rec


def _bulk(arrays: dict) -> tuple[float, str, float]:
    """(min bulk ESS, its parameter, max R-hat) over {name: (chains, draws[, k])} arrays."""
    import arviz as az

    ess, rhat = {}, {}
    for name, a in arrays.items():
        a = np.asarray(a, float)
        a = a.reshape(a.shape[0], a.shape[1], -1)
        for j in range(a.shape[2]):
            key = name if a.shape[2] == 1 else f"{name}[{j}]"
            ess[key] = float(az.ess(a[:, :, j], method="bulk"))
            rhat[key] = float(az.rhat(a[:, :, j]))
    worst = min(ess, key=ess.get)
    return ess[worst], worst, max(rhat.values())


# ------------------------------------------------------------------------------ models
def composite(sizes):
    from fogbayes.composite.cells import rate_data
    from fogbayes.composite.bayes import fit_bayes
    from fogbayes.composite.model import PAPER_ORDERS
    from fogbayes.simulate.scenarios import simulate

    c, w, s = sizes(4, 500, 500)
    data = rate_data(simulate("paper000", seed=11, dwell=20.0).recording, smooth_s=5.0)[0]

    def call(seed):
        return fit_bayes(data, PAPER_ORDERS, seed=seed, noise="cells", chains=c, warmup=w,
                         samples=s)

    def diag(f):
        post = f.idata.posterior  # sigma = monotone map of u_sigma: the same bulk ESS
        ess, worst, rhat = _bulk({k: post[k].values for k in ("sigma", "log_lam", "rho")})
        return {"ess_bulk_min": ess, "worst": worst, "r_hat_max": rhat,
                "divergences": f.divergences,
                "api": {"ess_min": f.ess_min, "rhat_max": f.rhat_max,
                        "converged": f.converged}}

    return (c, w, s), call, diag, {"n_cells": int(data.cell.max()) + 1, "n": int(data.cell.size)}


def allan(sizes):
    from fogbayes.allan.bayes import fit_bayes
    from fogbayes.allan.data import prepare
    from fogbayes.allan.model import TERMS
    from fogbayes.simulate.noise import allan_noise

    c, w, s = sizes(2, 400, 600)
    fs = 10.0
    y = allan_noise(4 * 2**14, fs, seed=21, flicker_span=1, Q=0.19, N=0.01, B=0.404, K=4.41)[:2**14]
    data = prepare(y, fs)

    def call(seed):
        return fit_bayes(data, TERMS, seed=seed, num_warmup=w, num_samples=s, num_chains=c)

    def diag(p):
        on = np.flatnonzero(p.mask > 0)
        logd = np.log(p.draws.reshape(c, s, 5)[:, :, on])
        ess, worst, rhat = _bulk({f"log_{TERMS[i]}": logd[:, :, k] for k, i in enumerate(on)})
        d = p.diagnostics
        return {"ess_bulk_min": ess, "worst": worst, "r_hat_max": rhat,
                "divergences": d["divergences"], "discrepancy": d["discrepancy"],
                "api": {"ess_min (numpyro n_eff)": d["ess_min"], "r_hat_max": d["r_hat_max"],
                        "converged": d["converged"], "gof_p": d["gof_p"]}}

    return (c, w, s), call, diag, {"n": y.size, "taus": int(data.tau.size)}


def arma(sizes):
    from scipy.signal import lfilter

    from fogbayes.arma.bayes import arma_posterior

    c, w, s = sizes(2, 500, 500)
    e = np.random.default_rng(0).standard_normal(600)
    x = lfilter([1.0, 0.4], [1.0, -0.6], e)  # x_t = 0.6 x_t-1 + a_t - (-0.4) a_t-1

    def call(seed):
        return arma_posterior(x, p=1, q=1, seed=seed, num_warmup=w, num_samples=s, num_chains=c)

    def diag(p):
        post = p.idata.posterior
        ess, worst, rhat = _bulk({k: post[k].values for k in ("pacf_phi", "pacf_theta",
                                                              "sigma2")})
        return {"ess_bulk_min": ess, "worst": worst, "r_hat_max": rhat,
                "divergences": p.divergences,
                "api": {"ess_bulk_min": p.ess_bulk_min, "rhat_max": p.rhat_max,
                        "converged": p.converged}}

    return (c, w, s), call, diag, {"n": x.size}


def thermal(sizes):
    from fogbayes.simulate import simulate
    from fogbayes.thermal.workflow import fit_recording

    c, w, s = sizes(2, 500, 1000)
    rec = simulate("thermal", seed=1, duration=3600.0, fs=1.0).recording

    def call(seed):
        return fit_recording(rec, model="thermal", bayes=True, seed=seed, num_chains=c,
                             num_warmup=w, num_samples=s)

    def diag(doc):
        # the document keeps ArviZ's summary numbers, not the draws: no per-parameter argmin
        cv = doc["bayes"]["convergence"]
        return {"ess_bulk_min": cv["ess_bulk_min"], "worst": "beta/sigma/phi",
                "r_hat_max": cv["r_hat_max"], "divergences": cv["divergences"],
                "api": cv | {"n_blocks": doc["bayes"]["n_blocks"]}}

    return (c, w, s), call, diag, {"n": rec.n}


MODELS = {"composite": composite, "allan": allan, "arma": arma, "thermal": thermal}


def bench(name: str, sizes) -> dict:
    (c, w, s), call, diag, info = MODELS[name](sizes)
    load0 = os.getloadavg()
    first, t1, comp1 = _timed_call(lambda: call(0))
    warm, t2, comp2 = _timed_call(lambda: call(1))
    d1, d2 = diag(first), diag(warm)
    row = {"model": name, "chains": c, "warmup": w, "draws": s, "data": info,
           "first_s": t1, "warm_s": t2, "first_compile": comp1, "warm_compile": comp2,
           "first": d1, "warm": d2, "ess_per_s": d2["ess_bulk_min"] / t2,
           "ess_per_s_excl_xla_compile": d2["ess_bulk_min"] / (t2 - comp2["xla_compile_s"]),
           "loadavg_before": load0, "loadavg_after": os.getloadavg()}
    print(json.dumps({"model": name, "first_s": round(t1, 2), "warm_s": round(t2, 2),
                      "warm_compile": comp2, "ess_bulk_min": round(d2["ess_bulk_min"], 1)}),
          flush=True)
    return row


def _versions() -> dict:
    import arviz
    import jaxlib
    import numpyro

    return {"python": platform.python_version(), "jax": jax.__version__,
            "jaxlib": jaxlib.__version__, "numpyro": numpyro.__version__,
            "arviz": arviz.__version__, "numpy": np.__version__,
            "fogbayes": fogbayes.__version__, "backend": jax.default_backend(),
            "machine": platform.processor() or platform.machine(), "cpus": os.cpu_count()}


def table(rows: list[dict]) -> str:
    head = ("| model | chains x (warmup + draws) | first s | warm s | warm compile s (n) "
            "| ess_bulk min (param) | r_hat max | div | ESS/s |")
    lines = [head, "|" + " --- |" * 9]
    for r in rows:
        w = r["warm"]
        extra = " +disc" if w.get("discrepancy") else ""
        lines.append(
            f"| {r['model']}{extra} | {r['chains']} x ({r['warmup']} + {r['draws']}) "
            f"| {r['first_s']:.1f} | {r['warm_s']:.1f} "
            f"| {r['warm_compile']['xla_compile_s']:.1f} ({r['warm_compile']['xla_compiles']}) "
            f"| {w['ess_bulk_min']:.0f} ({w['worst']}) | {w['r_hat_max']:.3f} "
            f"| {w['divergences']} | {r['ess_per_s']:.0f} |")
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--models", nargs="+", choices=list(MODELS), default=list(MODELS))
    ap.add_argument("--quick", action="store_true", help="2 chains x (100 + 100) everywhere")
    ap.add_argument("--chains", type=int, help="override every model's chain count")
    ap.add_argument("--warmup", type=int, help="override every model's warm-up length")
    ap.add_argument("--samples", type=int, help="override every model's draws per chain")
    ap.add_argument("--json", metavar="PATH", help="also write the results as JSON")
    args = ap.parse_args()
    warnings.filterwarnings("ignore")

    def sizes(c, w, s):
        if args.quick:
            c, w, s = 2, 100, 100
        return (args.chains or c, args.warmup or w, args.samples or s)

    env = _versions()
    load0 = os.getloadavg()
    t0 = time.perf_counter()
    rows = [bench(m, sizes) for m in args.models]
    load1 = os.getloadavg()
    print()
    print(", ".join(f"{k} {v}" for k, v in env.items()))
    print(f"load average (1, 5, 15 min) before: {load0[0]:.2f} {load0[1]:.2f} {load0[2]:.2f}; "
          f"after: {load1[0]:.2f} {load1[1]:.2f} {load1[2]:.2f}; "
          f"total {time.perf_counter() - t0:.0f} s")
    print()
    print(table(rows))
    for r in rows:
        big = [f"{f} {t:.1f} s" for f, t in r["warm_compile"]["longest"] if t >= 0.5]
        if big:
            print(f"\n{r['model']}: the warm call compiled again: {', '.join(big)}")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump({"env": env, "quick": args.quick, "loadavg_before": load0,
                       "loadavg_after": load1, "rows": rows}, fh, indent=1, default=float)


if __name__ == "__main__":
    main()
