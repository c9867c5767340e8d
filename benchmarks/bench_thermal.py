"""Thermal models: timings (6 h at 10 Hz, 1 000-sensor batch) and accuracy studies.

    python benchmarks/bench_thermal.py speed  [--scale 1.0]   # fit/compensate, batch vs loop
    python benchmarks/bench_thermal.py oracle [--seeds 5]     # thermal / bias-t / oracle Bs
    python benchmarks/bench_thermal.py coverage [--runs 80]   # posterior 90 % coverage

speed:
  1. one simulated 6 h record at 10 Hz ("thermal" scenario + a Shupe term): wall time of
     ``fit_recording`` (bias-t, thermal, thermal with the AR(1) posterior) and of
     ``compensate_recording``; the jitted compensator alone against a plain NumPy
     evaluation of the same polynomial and a memory copy, in bytes moved per second
     (every input array read + the output written; a copy reads one array and writes one);
  2. 1 000 sensors of one chamber run (shared profile, own coefficients and coloured
     noise, 10 s block means): one ``jit(vmap(lstsq))`` call against a loop over sensors of
     the same jitted ``lstsq`` and against a loop of ``numpy.linalg.lstsq`` (results checked
     equal). Best of ``--repeat`` runs after a warm-up; compilation reported apart.
oracle: simulated paper-004 runs (TMP461-quantised thermometer), several seeds and noise
  levels: 1 s bias stability of bias-t, thermal (default and paper processing) relative to
  the oracle (true bias removed), and the improvement % as the paper reports it.
coverage: like tests/test_thermal_bayes.py with more runs, AR(1) and white noise.
Ratios, not seconds, carry over between machines (this one: 2 shared cores).
"""

from __future__ import annotations

import argparse
import json
import platform
import time

import jax
import numpy as np

import fogbayes  # noqa: F401  (float64)
from _timing import best_of  # benchmarks/ is on sys.path when a script runs
from fogbayes.thermal.compensate import compensate_bias
from fogbayes.inference.lsq import lstsq, lstsq_gram
from fogbayes.stats.stability import bias_stability
from fogbayes.simulate import simulate
from fogbayes.simulate.noise import markov_noise
from fogbayes.thermal.workflow import compensate_recording, fit_recording


def _timed(fn):
    t0 = time.perf_counter()
    out = fn()
    return out, time.perf_counter() - t0


def speed(scale: float, repeat: int, sensors: int) -> dict:
    out = {"machine": platform.processor() or platform.machine(), "jax": jax.__version__}
    sim = simulate("thermal", seed=0, fs=10.0, duration=6 * 3600.0 * scale,
                   effects={"temperature_rate": {"coeff": 0.3}})
    rec = sim.recording
    out["record"] = {"n": rec.n, "hours": rec.n / 10.0 / 3600.0}
    for label, kwargs in (("bias-t", {"model": "bias-t"}), ("thermal", {"model": "thermal"}),
                          ("thermal+bayes", {"model": "thermal", "bayes": True})):
        fit_recording(rec, **kwargs)  # warm-up: compilation
        doc, t = _timed(lambda kw=kwargs: fit_recording(rec, **kw))
        out[f"fit_{label}_s"] = round(t, 3)
    compensate_recording(rec, doc)
    out["compensate_recording_s"] = round(best_of(lambda: compensate_recording(rec, doc), repeat), 3)

    # the compensator alone: y - X(z) @ coef with z = (T, dT/dt)
    from fogbayes.models.basis_document import basis_from_dict
    from fogbayes.models.polynomial import evaluate  # noqa: F401

    basis = basis_from_dict(doc["params"]["basis"])
    coef = np.asarray(doc["params"]["coef"])
    z = np.ascontiguousarray(np.column_stack([rec.temperature, np.gradient(rec.temperature)]))
    y = rec.rate("deg/h")
    jax.block_until_ready(compensate_bias(coef, z, y, basis))
    t_jax = best_of(lambda: compensate_bias(coef, z, y, basis), repeat)
    c, s = np.asarray(basis.centre), np.asarray(basis.scale)

    def numpy_version():  # the same centred polynomial, term by term, in plain NumPy
        zs = (z - c) / s
        bias = np.zeros_like(y)
        for k, e in enumerate(basis.terms):
            col = coef[k]
            for j, ej in enumerate(e):
                if ej:
                    col = col * zs[:, j] ** int(ej)
            bias += col
        return y - bias

    np.testing.assert_allclose(numpy_version(), compensate_bias(coef, z, y, basis), atol=1e-9)
    t_np = best_of(numpy_version, repeat)
    moved = (z.nbytes + y.nbytes + y.nbytes)  # read z and y, write the output
    blob = np.zeros(moved // 16)  # a copy of half the bytes reads and writes `moved` bytes
    t_copy = best_of(lambda: blob.copy(), repeat)
    out["compensator"] = {"jax_s": t_jax, "numpy_s": t_np, "copy_s": t_copy,
                          "jax_GB_s": moved / t_jax / 1e9, "numpy_GB_s": moved / t_np / 1e9,
                          "copy_GB_s": moved / t_copy / 1e9,
                          "jax_Msamples_s": y.size / t_jax / 1e6,
                          "numpy_over_jax": t_np / t_jax}
    out["batch"] = batch_fit(sensors, repeat)
    return out


def batch_fit(sensors: int, repeat: int) -> dict:
    """1 000 sensors in one chamber: shared profile, own coefficients, coloured noise."""
    from fogbayes.models.polynomial import design
    from fogbayes.thermal.model import ThermalSpec, thermal_basis
    from fogbayes.preprocess import block_average
    from fogbayes.preprocess.temperature_rate import temperature_rate_per_min

    prof = simulate("thermal", seed=1, fs=1.0, duration=6 * 3600.0, noise={}).recording
    rng = np.random.default_rng(2)
    Xs = []
    for k in range(sensors):  # each sensor has its own thermometer: offset, noise, lag
        T = prof.temperature + rng.normal() * 0.5 + 0.03 * rng.normal(size=prof.n)
        r = temperature_rate_per_min(prof.time, T, method="savgol", window_s=60.0)
        b = block_average(np.column_stack([T, r]), 10.0, time=prof.time)
        Xs.append(np.asarray(design(b.mean, thermal_basis(ThermalSpec(2, 2), b.mean))))
    X = np.stack(Xs)
    coefs = rng.normal(size=(sensors, X.shape[2])) * [1.0, 0.5, 0.2, 0.3, 0.05]
    noise = np.stack([markov_noise(X.shape[1], 0.1, seed=k, sigma=0.2, tau_c=300.0)
                      for k in range(sensors)])
    Y = np.einsum("knp,kp->kn", X, coefs) + noise + 0.05 * rng.normal(size=noise.shape)
    vm = jax.jit(jax.vmap(lstsq_gram))  # batched QR is slow on CPU; see lstsq_gram
    vm_qr = jax.jit(jax.vmap(lstsq))
    one = jax.jit(lstsq)
    jax.block_until_ready(vm_qr(X, Y).params)
    t_vm_qr = best_of(lambda: jax.block_until_ready(vm_qr(X, Y).params), repeat)
    (_, t_c1) = _timed(lambda: jax.block_until_ready(vm(X, Y).params))
    (_, t_c2) = _timed(lambda: jax.block_until_ready(one(X[0], Y[0]).params))
    t_vm = best_of(lambda: jax.block_until_ready(vm(X, Y).params), repeat)
    t_loop = best_of(lambda: [jax.block_until_ready(one(x, y).params) for x, y in zip(X, Y)],
                     repeat)
    t_np = best_of(lambda: [np.linalg.lstsq(x, y, rcond=None) for x, y in zip(X, Y)], repeat)
    ref = np.stack([np.linalg.lstsq(x, y, rcond=None)[0] for x, y in zip(X, Y)])
    err = float(np.max(np.abs(np.asarray(vm(X, Y).params) - ref)))
    return {"sensors": sensors, "blocks": X.shape[1], "terms": X.shape[2],
            "compile_vmap_s": t_c1, "compile_single_s": t_c2, "vmap_s": t_vm,
            "vmap_qr_s": t_vm_qr, "loop_jax_s": t_loop, "loop_numpy_s": t_np,
            "loop_over_vmap": t_loop / t_vm, "loop_over_vmap_qr": t_loop / t_vm_qr,
            "numpy_loop_over_vmap": t_np / t_vm, "max_abs_diff_vs_numpy": err}


NOISE = {"paper": {"N": 0.008, "B": 0.05},
         "markov": {"N": 0.008, "B": 0.05, "markov": {"sigma": 0.3, "tau_c": 300.0}},
         "high": {"N": 0.02, "B": 0.15}}


def oracle(seeds: int) -> dict:
    rows = []
    for noise, spec in NOISE.items():
        for seed in range(seeds):
            sim = simulate("paper004", seed=seed, noise=spec)
            rec = sim.recording
            rec = rec.replace(temperatures=np.round(rec.temperatures / 0.0625) * 0.0625)
            rate = rec.rate("deg/h")
            bo = bias_stability(rate - sim.truth.error(), rec.time)
            row = {"noise": noise, "seed": seed, "before": bias_stability(rate, rec.time),
                   "oracle": bo}
            for label, kw in (("bias-t", {"model": "bias-t"}), ("thermal", {"model": "thermal"}),
                              ("thermal_paper", {"model": "thermal", "processing": "paper"})):
                doc = fit_recording(rec, **kw)
                after = bias_stability(compensate_recording(rec, doc)["output"], rec.time)
                row[label] = after / bo
                row[label + "_improvement_pct"] = doc["metrics"]["full"]["stability"][0]["improvement_pct"]
            rows.append(row)
            print(json.dumps({k: (round(v, 4) if isinstance(v, float) else v) for k, v in row.items()}))
    return {"rows": rows}


def coverage(runs: int) -> dict:
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
    from test_thermal_bayes import _run  # the test's own data path, more runs

    from fogbayes.inference.bayes import fit_linear_bayes_batch

    data = [_run(1000 + k) for k in range(runs)]
    n = min(d[1].size for d in data)
    X = np.stack([d[0][:n] for d in data])
    y = np.stack([d[1][:n] for d in data])
    truth = np.stack([d[2] for d in data])
    out = {}
    for noise in ("ar", "white"):
        fit = fit_linear_bayes_batch(X, y, seed=1, noise=noise, p=1, num_warmup=400,
                                     num_samples=800)
        inside = (fit.interval[..., 0] <= truth) & (truth <= fit.interval[..., 1])
        out[noise] = {"coverage": float(inside.mean()),
                      "per_coefficient": inside.mean(0).round(3).tolist(),
                      "converged": float(np.mean([c.converged for c in fit.convergence]))}
        print(noise, out[noise])
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("what", choices=["speed", "oracle", "coverage"])
    ap.add_argument("--scale", type=float, default=1.0, help="record length x 6 h")
    ap.add_argument("--sensors", type=int, default=1000)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--seeds", type=int, default=5)
    ap.add_argument("--runs", type=int, default=80)
    a = ap.parse_args()
    res = {"speed": lambda: speed(a.scale, a.repeat, a.sensors), "oracle": lambda: oracle(a.seeds),
           "coverage": lambda: coverage(a.runs)}[a.what]()
    print(json.dumps(res, indent=1, default=float))


if __name__ == "__main__":
    main()
