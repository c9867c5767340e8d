"""What fogbayes' XLA programs do on an accelerator, against references in the same run.

    python benchmarks/bench_gpu.py [--sensors 256] [--n 1048576] [--repeat 5] [--json OUT]

Runs on whatever device JAX uses by default (a GPU where one is seen); every figure is a
ratio to a reference measured in the same process:

1. **Bias compensation on the device** (``bias_compensator(basis).batch``, thermal (2, 2):
   six terms in T and dT/dt): ``--sensors`` x ``--n`` samples already on the device,
   against a device-to-device copy of the output array (``jnp.copy``). Bytes: the
   compensator reads y and the two covariates and writes the output (4 x 8 bytes a
   sample); the copy reads and writes y (2 x 8). float64 and float32.
2. **As users call it** (``compensate_bias`` on host NumPy arrays: transfers both ways
   and the first call's compilation counted), against plain NumPy on the host
   (``y - design(z) @ coef``), same sensors, same samples.
3. **Batched least squares** (``fogbayes.batch.xla.batched_solver``, the vmapped fit of
   ``fogbayes batch``; gram and QR): one call over ``--fits`` sensors x 3 600 blocks
   against a loop of the jitted single-sensor solve.
4. **Overlapping Allan deviation** (``allan_deviation``, octave taus, 90 % intervals) of
   ``--adev-n`` white samples: the jitted kernels on the device (``method="auto"`` where
   JAX sees a GPU) against the cache-blocked CPU accumulators (``method="blocked"``,
   Numba, all cores of the same machine).

Agreement is checked alongside: the largest difference between each pair of paths.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import time

import jax
import jax.numpy as jnp
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

import fogbayes  # noqa: E402  (float64 on)
from fogbayes.thermal.compensate import bias_compensator, compensate_bias  # noqa: E402
from fogbayes.models.polynomial import design  # noqa: E402
from fogbayes.thermal.model import ThermalSpec, thermal_basis  # noqa: E402


def best(fn, repeat: int) -> tuple[float, object]:
    out, times = None, []
    for _ in range(repeat):
        t = time.perf_counter()
        out = jax.block_until_ready(fn())
        times.append(time.perf_counter() - t)
    return min(times), out


def data(sensors: int, n: int, seed: int = 0):
    rng = np.random.default_rng(seed)
    T = rng.uniform(-40.0, 60.0, (sensors, n))
    Tdot = rng.uniform(-2.0, 2.0, (sensors, n))
    z = np.stack([T, Tdot], axis=-1)
    basis = thermal_basis(ThermalSpec(2, 2), z.reshape(-1, 2)[:100_000])
    coef = rng.normal(0.0, 1.0, (sensors, basis.n_terms))
    y = rng.normal(0.0, 1.0, (sensors, n))
    return basis, coef, z, y


def compensation(args) -> dict:
    basis, coef, z, y = data(args.sensors, args.n)
    comp = bias_compensator(basis)
    out = {"sensors": args.sensors, "n_each": args.n}
    copy = jax.jit(jnp.copy)
    for dtype in (np.float64, np.float32):
        dc, dz, dy = (jax.device_put(a.astype(dtype)) for a in (coef, z, y))
        t = time.perf_counter()
        jax.block_until_ready(comp.batch(dc, dz, dy))
        t_first = time.perf_counter() - t
        t_comp, res = best(lambda: comp.batch(dc, dz, dy), args.repeat)
        jax.block_until_ready(copy(dy))
        t_copy, _ = best(lambda: copy(dy), args.repeat)
        isz = np.dtype(dtype).itemsize
        samples = args.sensors * args.n
        ref = y[:2] - np.einsum("snp,sp->sn", design(z[:2].reshape(-1, 2), basis).reshape(
            2, args.n, -1), coef[:2])
        err = float(np.max(np.abs(np.asarray(res[:2], float) - ref)))
        row = {"first_call_s": t_first, "compensate_s": t_comp, "copy_s": t_copy,
               "Gsamples_s": samples / t_comp / 1e9,
               "GB_s": 4 * isz * samples / t_comp / 1e9,
               "copy_GB_s": 2 * isz * samples / t_copy / 1e9,
               "samples_vs_copy": t_copy / t_comp,
               "bytes_vs_copy": (4 * isz / t_comp) / (2 * isz / t_copy),
               "max_abs_err_vs_numpy": err}
        out[np.dtype(dtype).name] = row
        print(f"[compensate {np.dtype(dtype).name}] {row['Gsamples_s']:.2f} Gsamples/s, "
              f"{row['GB_s']:.0f} GB/s; copy {row['copy_GB_s']:.0f} GB/s; samples/s "
              f"{row['samples_vs_copy']:.2f}x a copy of y, bytes {row['bytes_vs_copy']:.2f}x; "
              f"first call {t_first:.2f} s; |err| {err:.1e}", flush=True)
        del dc, dz, dy, res
    # as users call it: host NumPy in and out, a fresh basis object (compilation counted)
    k = max(1, min(args.sensors, args.host_sensors))
    hc, hz, hy = coef[:k], z[:k], y[:k]
    bias_compensator.cache_clear()
    t = time.perf_counter()
    first = compensate_bias(hc, hz, hy, basis)
    t_first = time.perf_counter() - t
    t_pub, _ = best(lambda: compensate_bias(hc, hz, hy, basis), args.repeat)

    def numpy_path():
        return np.stack([hy[s] - design(hz[s], basis) @ hc[s] for s in range(k)])

    t_np, ref = best(numpy_path, max(1, args.repeat // 2))
    out["public_host"] = {"sensors": k, "first_call_s": t_first, "warm_s": t_pub,
                          "numpy_s": t_np, "warm_speedup_vs_numpy": t_np / t_pub,
                          "first_call_speedup_vs_numpy": t_np / t_first,
                          "max_abs_diff": float(np.max(np.abs(first - ref)))}
    print(f"[compensate_bias, host arrays] {k} sensors: first call {t_first:.2f} s, warm "
          f"{t_pub:.3f} s; NumPy {t_np:.2f} s -> {t_np / t_pub:.1f}x warm, "
          f"{t_np / t_first:.1f}x first", flush=True)
    return out


def least_squares(args) -> dict:
    from functools import partial

    from fogbayes.batch.xla import batched_solver, solve_one, unit_basis

    basis, _, z, y = data(args.fits, 3600, seed=1)
    unit = unit_basis(basis)
    dev = [jnp.asarray(a) for a in (z, y, np.ones((args.fits, 3600)),
                                    np.tile(basis.centre, (args.fits, 1)),
                                    np.tile(basis.scale, (args.fits, 1)),
                                    np.full(args.fits, 3600.0))]
    out = {"sensors": args.fits, "blocks": 3600, "n_params": unit.n_terms}
    for solver in ("gram", "qr"):
        vm = batched_solver(unit, solver)
        t = time.perf_counter()
        jax.block_until_ready(vm(*dev))
        t_first = time.perf_counter() - t
        t_vm, res = best(lambda vm=vm: vm(*dev), args.repeat)
        one = jax.jit(partial(solve_one, unit=unit, solver=solver))
        per = [[a[s] for a in dev] for s in range(args.fits)]
        jax.block_until_ready(one(*per[0]))
        t_loop, res_loop = best(lambda: [one(*p)[0] for p in per], max(1, args.repeat // 2))
        diff = float(np.max(np.abs(np.asarray(res[0]) - np.stack(res_loop))))
        out[solver] = {"first_call_s": t_first, "vmap_s": t_vm, "loop_s": t_loop,
                       "loop_over_vmap": t_loop / t_vm, "fits_per_s": args.fits / t_vm,
                       "max_abs_diff": diff}
        print(f"[lstsq {solver}] {args.fits} fits in {t_vm * 1e3:.2f} ms "
              f"({args.fits / t_vm:.0f} fits/s; first call {t_first:.2f} s); loop of jitted "
              f"fits {t_loop * 1e3:.0f} ms -> {t_loop / t_vm:.0f}x; |diff| {diff:.1e}",
              flush=True)
    return out


def allan(args) -> dict:
    from fogbayes.stats.allan import allan_deviation

    y = np.random.default_rng(2).normal(0.0, 1.0, args.adev_n)
    t = time.perf_counter()
    gpu = allan_deviation(y, 100.0, taus="octave")
    t_first = time.perf_counter() - t
    t_gpu, gpu = best(lambda: allan_deviation(y, 100.0, taus="octave"), args.repeat)
    allan_deviation(y[:100_000], 100.0, taus="octave", method="blocked")  # compile the loops
    t_cpu, cpu = best(lambda: allan_deviation(y, 100.0, taus="octave", method="blocked"),
                      args.repeat)
    rel = float(np.max(np.abs(gpu.dev / cpu.dev - 1.0)))
    out = {"n": args.adev_n, "device_first_call_s": t_first, "device_s": t_gpu,
           "cpu_blocked_s": t_cpu, "cpu_cores": os.cpu_count(),
           "device_speedup_vs_cpu": t_cpu / t_gpu, "max_rel_diff": rel}
    print(f"[allan_deviation] {args.adev_n:.0e} samples: device {t_gpu:.3f} s (first "
          f"{t_first:.2f} s), CPU blocked ({os.cpu_count()} cores) {t_cpu:.3f} s -> "
          f"{t_cpu / t_gpu:.2f}x; rel diff {rel:.1e}", flush=True)
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sensors", type=int, default=256)
    ap.add_argument("--n", type=int, default=1 << 20)
    ap.add_argument("--host-sensors", type=int, default=16)
    ap.add_argument("--fits", type=int, default=1000)
    ap.add_argument("--adev-n", type=int, default=100_000_000)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--json", default=None)
    args = ap.parse_args()
    dev = jax.devices()[0]
    out = {"device": str(getattr(dev, "device_kind", dev.platform)), "backend": dev.platform,
           "jax": jax.__version__, "numpy": np.__version__, "fogbayes": fogbayes.__version__,
           "machine": platform.machine(), "cpu_cores": os.cpu_count()}
    print(json.dumps(out), flush=True)
    out["compensation"] = compensation(args)
    out["least_squares"] = least_squares(args)
    out["allan"] = allan(args)
    if args.json:
        with open(args.json, "w") as f:
            json.dump(out, f, indent=1)


if __name__ == "__main__":
    main()
