"""Fleets: one vmapped fit of many same-shape sensors, and local vs Dask fleet wall time.

    python benchmarks/bench_batch.py vector [--sensors 1000] [--hours 1] [--workflow 40]
    python benchmarks/bench_batch.py fleet  [--recordings 16] [--hours 1] [--workers 2]

``vector``: ``--sensors`` simulated ``thermal`` chamber runs (1 Hz, each sensor with its own
quadratic bias in T and its own noise), model ``thermal`` (2, 2) on 1 s block means
(5 coefficients, 3 600 blocks per hour). Times, best of 3 after a warm-up:

1. the batched least-squares stage (:func:`fogbayes.batch.xla.batched_solver`): one
   ``jit(vmap)`` call over all sensors, against a Python loop over the same jitted
   single-sensor solve (inputs already on the device), for both solvers;
2. the compiled CPU stage (:func:`fogbayes.batch.kernels.fit_gram`, sensors on all
   cores): one call over all sensors against a loop of one-sensor calls;
3. the whole vectorised fit (:func:`fogbayes.batch.fit_vectorized`: covariates, blocks,
   Pauta flags, refit, metrics and documents), with the compiled loops (``numba``, the CPU
   default) and with the XLA program (``gram``), against a loop over the per-recording
   workflow ``fit_recording`` -- timed on ``--workflow`` sensors and scaled to all.

Identical numbers: the largest coefficient difference between the paths.

``fleet``: ``run_batch`` (task ``fit``, ``bias-t``) over ``--recordings`` files, in-process
serial against a local Dask cluster of ``--workers`` processes (cluster start included, and
measured alone), and the largest difference between their fit documents' coefficients.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import tempfile
import time
from functools import partial
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np

import fogbayes
from fogbayes.batch import fit_vectorized, kernels, run_batch
from fogbayes.batch.vectorized import _exponents
from fogbayes.batch.xla import batched_solver, solve_one, unit_basis
from fogbayes.data.io import save
from fogbayes.thermal.model import ThermalSpec, thermal_basis
from fogbayes.simulate.scenarios import simulate
from fogbayes.thermal.data import (
    fit_blocks,
    make_processing,
    sample_covariates,
)
from fogbayes.thermal.workflow import fit_recording


def best(fn, repeat=3, *, block=True):
    """Best of ``repeat`` calls after a warm-up. ``block``: wait for JAX's asynchronous
    results; off for functions that return host data only (walking a fleet's documents,
    182 000 leaves for 1 000 sensors, took 0.13 s and was timed as fitting)."""
    fn()  # warm-up (compilation)
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        out = fn()
        if block:
            jax.block_until_ready(out)
        times.append(time.perf_counter() - t)
    return min(times), out


def sensors(n: int, hours: float, seed: int = 0) -> list:
    rng = np.random.default_rng(seed)
    recs = []
    for s in range(n):  # each sensor its own bias polynomial and noise draw
        c = [rng.normal(0.5, 0.2), rng.normal(0.01, 0.005), rng.normal(2e-4, 1e-4)]
        recs.append(simulate("thermal", seed=seed * 100_000 + s, duration=3600.0 * hours, fs=1.0,
                             effects={"temperature_order": {"coeffs": c, "T_ref": 20.0}},
                             sensor_id=f"s{s}").recording)
    return recs


def vector(args) -> dict:
    t = time.perf_counter()
    recs = sensors(args.sensors, args.hours)
    t_sim = time.perf_counter() - t
    # the whole pipeline first, in a process that holds only the recordings (the stage
    # comparisons below keep thousands of device arrays alive)
    out = {"sensors": args.sensors, "simulate_s": t_sim, "pipeline": pipeline(recs, args)}
    out.update(stages(recs, args))
    return out


def stages(recs, args) -> dict:
    spec, proc = ThermalSpec(2, 2), make_processing("default")
    t = time.perf_counter()
    blocks = []
    for r in recs:
        y = r.rate("deg/h")
        blocks.append(fit_blocks(r, y, sample_covariates(r, spec, proc), spec, proc, None))
    bases = [thermal_basis(spec, b.z) for b in blocks]
    t_prep = time.perf_counter() - t
    assert len({b.y.size for b in blocks}) == 1, "same-shape sensors expected"
    stack = [np.stack([b.z for b in blocks]), np.stack([b.y for b in blocks]),
             np.stack([b.count.astype(float) for b in blocks]),
             np.array([bs.centre for bs in bases]), np.array([bs.scale for bs in bases]),
             np.full(len(blocks), float(blocks[0].y.size))]
    dev = [jnp.asarray(a) for a in stack]
    unit = unit_basis(bases[0])
    out = {"blocks_per_sensor": int(blocks[0].y.size), "n_params": unit.n_terms,
           "prepare_blocks_s": t_prep}
    for solver in ("gram", "qr"):
        vm = batched_solver(unit, solver)
        t = time.perf_counter()
        jax.block_until_ready(vm(*dev))
        t_compile = time.perf_counter() - t
        t_vm, res_vm = best(lambda vm=vm: vm(*dev))
        one = jax.jit(partial(solve_one, unit=unit, solver=solver))
        per = [[a[s] for a in dev] for s in range(args.sensors)]  # on the device already
        t_loop, res_loop = best(lambda one=one, per=per: [one(*p)[0] for p in per])
        diff = float(np.max(np.abs(np.asarray(res_vm[0]) - np.stack(res_loop))))
        out[solver] = {"compile_vmap_s": t_compile, "vmap_s": t_vm, "loop_jit_s": t_loop,
                       "loop_over_vmap": t_loop / t_vm, "max_abs_diff_coef": diff}
        print(f"[{solver}] one vmapped call {t_vm * 1e3:.1f} ms, loop of jitted single fits "
              f"{t_loop * 1e3:.1f} ms -> {t_loop / t_vm:.2f}x; max |diff| {diff:.2e}", flush=True)
    # the compiled CPU stage (fogbayes.batch.kernels): one call over all sensors against a
    # loop calling it sensor by sensor
    z_c = np.ascontiguousarray(stack[0].transpose(0, 2, 1))
    per_sensor = (z_c, *stack[1:])  # sliced by sensor; then exponents and rcond
    exps = _exponents(unit)
    t_all, res_all = best(lambda: kernels.fit_gram(*per_sensor, exps, 1e-10))
    t_one, res_one = best(lambda: [kernels.fit_gram(*(a[s:s + 1] for a in per_sensor), exps,
                                                    1e-10)[0] for s in range(args.sensors)])
    diff = float(np.max(np.abs(res_all[0] - np.concatenate(res_one))))
    diff_xla = float(np.max(np.abs(res_all[0] - np.asarray(res_vm[0]))))
    out["numba"] = {"all_s": t_all, "loop_s": t_one, "loop_over_all": t_one / t_all,
                    "max_abs_diff_coef": diff, "max_abs_diff_coef_vs_xla": diff_xla}
    print(f"[numba] one call over all sensors {t_all * 1e3:.1f} ms, loop of one-sensor calls "
          f"{t_one * 1e3:.1f} ms -> {t_one / t_all:.2f}x; max |diff| {diff:.2e} (vs XLA "
          f"{diff_xla:.2e})", flush=True)
    return out


def pipeline(recs, args) -> dict:
    sub = recs[:args.workflow]
    fit_recording(sub[0], model="thermal")  # warm-up: compilations of the per-sensor path
    t = time.perf_counter()
    ref = [fit_recording(r, model="thermal") for r in sub]
    t_wf = (time.perf_counter() - t) * args.sensors / len(sub)
    pipe = {"workflow_loop_s_scaled": t_wf, "workflow_sensors_timed": len(sub)}
    for solver in ("numba", "gram"):
        t = time.perf_counter()
        docs = fit_vectorized(recs, model="thermal", solver=solver)
        t_first = time.perf_counter() - t
        t_vec, docs = best(lambda solver=solver: fit_vectorized(recs, model="thermal",
                                                                 solver=solver), block=False)
        diff = max(float(np.max(np.abs(np.subtract(a["params"]["coef"], b["params"]["coef"]))))
                   for a, b in zip(ref, docs))
        pipe[solver] = {"fit_vectorized_first_s": t_first, "fit_vectorized_s": t_vec,
                        "workflow_over_vectorized": t_wf / t_vec, "max_abs_diff_coef": diff}
        print(f"[pipeline/{solver}] workflow loop {t_wf:.2f} s (from {len(sub)} sensors), "
              f"fit_vectorized {t_vec:.3f} s (first call {t_first:.2f} s) -> "
              f"{t_wf / t_vec:.1f}x; max |diff| {diff:.2e}", flush=True)
    return pipe


def fleet(args) -> dict:
    from fogbayes.batch import dask_client

    tmp = Path(tempfile.mkdtemp(prefix="bench_batch_"))
    for s in range(args.recordings):
        save(simulate("thermal", seed=s, duration=3600.0 * args.hours, fs=1.0).recording,
             tmp / "runs" / f"r{s:03d}.csv")
    t = time.perf_counter()
    with dask_client(None, args.workers):
        pass
    t_start = time.perf_counter() - t
    res = {}
    for engine in ("local", "dask"):
        t = time.perf_counter()
        summary = run_batch(tmp / "runs", model="bias-t", out=tmp / engine, engine=engine,
                            workers=args.workers)
        res[engine] = time.perf_counter() - t
        assert summary["n_error"] == 0
    diff = 0.0
    for f in sorted((tmp / "local").glob("*.fit.json")):
        a = json.loads(f.read_text())["params"]["coef"]
        b = json.loads((tmp / "dask" / f.name).read_text())["params"]["coef"]
        diff = max(diff, float(np.max(np.abs(np.subtract(a, b)))))
    out = {"recordings": args.recordings, "hours": args.hours, "workers": args.workers,
           "local_s": res["local"], "dask_s": res["dask"], "dask_cluster_start_close_s": t_start,
           "local_over_dask": res["local"] / res["dask"], "max_abs_diff_coef": diff}
    print(f"[fleet] {args.recordings} recordings: local serial {res['local']:.1f} s, dask "
          f"{args.workers} workers {res['dask']:.1f} s (cluster start+close alone {t_start:.1f} s)"
          f" -> {res['local'] / res['dask']:.2f}x; max |diff| {diff:.1e}", flush=True)
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("what", choices=["vector", "fleet", "all"])
    ap.add_argument("--sensors", type=int, default=1000)
    ap.add_argument("--hours", type=float, default=1.0)
    ap.add_argument("--workflow", type=int, default=40)
    ap.add_argument("--recordings", type=int, default=16)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--json", default=None)
    args = ap.parse_args()
    info = {"machine": platform.machine(), "cpus": os.cpu_count(), "python": platform.python_version(),
            "jax": jax.__version__, "fogbayes": fogbayes.__version__,
            "device": str(jax.devices()[0]), "loadavg_start": os.getloadavg()}
    print(info, flush=True)
    out = {"info": info}
    if args.what in ("vector", "all"):
        out["vector"] = vector(args)
    if args.what in ("fleet", "all"):
        out["fleet"] = fleet(args)
    out["info"]["loadavg_end"] = os.getloadavg()
    print("load average at the end:", out["info"]["loadavg_end"])
    if args.json:
        Path(args.json).write_text(json.dumps(out, indent=2))


if __name__ == "__main__":
    main()
