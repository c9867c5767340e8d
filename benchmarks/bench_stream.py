"""Streaming compensation and Allan deviation: bounded memory, throughput, speed vs allantools.

    python benchmarks/bench_stream.py large    [--sizes 2e8 2e9] [--dir /tmp/fogbayes_stream]
    python benchmarks/bench_stream.py roofline [--n 16777216] [--repeat 5]
    python benchmarks/bench_stream.py adev     [--n 1e7] [--repeat 3]

large: for each size, a record of float32 output and temperature columns (a directory of
  .npy files, 8 bytes per sample) and a bias-t fit; one subprocess per size runs
  ``stream_allan`` (octave taus up to ``max_lag`` = 2^22, rows as consecutive samples) and
  ``compensate_stream`` (3-sigma flags, float64 output + outlier columns, no time copy) and
  prints its peak RSS (VmHWM) and times. Then equality with the in-memory paths on a prefix
  that fits in memory (``--prefix`` samples, its own file): ADEV vs
  ``fogbayes.stats.allan_variance`` and the compensated output and flags vs
  ``compensate_recording``. Disk: 8 + 9 bytes per sample (inputs + outputs), checked with
  ``shutil.disk_usage`` first; files are removed afterwards unless ``--keep``.
roofline: compensation throughput in bytes moved per second (every input array read plus
  every output written) on an in-memory record processed in chunks as the stream does,
  against ``np.copyto`` of the same number of bytes in the same run and a plain NumPy
  version: bias-t (cubic in T: 24 bytes per sample), thermal (2, 2) in T and dT/dt
  (32 bytes), each with the library's (fused, term-by-term) compensator and the former
  design-matrix form ``y - X(z) @ coef``, and the composite Halley inversion (``Compensator.stream``,
  U's buffer donated: 32 bytes). Also end to end from a page-cached file to a file.
adev: overlapping ADEV of 1e7 samples vs allantools (octave and 20 per decade), for
  ``fogbayes.stats.allan_variance`` and ``fogbayes.stream.allan_variance_fast``; the
  largest relative difference to allantools is printed (must be < 1e-9).

Ratios measured in one run carry over between machines; absolute times on this shared
2-core box drift 2-3x with the load, which is printed.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

import fogbayes  # noqa: F401  (float64)
from _timing import best_of  # benchmarks/ is on sys.path when a script runs


def header() -> dict:
    import jax

    return {"machine": platform.processor() or platform.machine(), "cpus": os.cpu_count(),
            "python": platform.python_version(), "numpy": np.__version__,
            "jax": jax.__version__, "load_average": os.getloadavg()}


# ------------------------------------------------------------------------------- large
def bias_t_fit() -> dict:
    from fogbayes.models.basis_document import coefficient_document
    from fogbayes.thermal.model import bias_t_spec, thermal_basis
    from fogbayes.thermal.data import make_processing

    spec = bias_t_spec(3)
    basis = thermal_basis(spec, np.array([[-40.0], [60.0]]))
    return {"model": "bias-t", "processing": make_processing()._asdict(),
            "params": {"spec": spec._asdict(), **coefficient_document(
                basis, np.array([0.5, 0.3, 0.02, -0.01]), valid_range={"T": (-40.0, 60.0)})}}


def make_record(d: Path, n: int, *, block: int = 1 << 24, seed: int = 0) -> None:
    """output (deg/h) = bias(T) + white + flicker-ish walk; T a slow chamber cycle; float32."""
    d.mkdir(parents=True, exist_ok=True)
    from fogbayes.stream.writers import NpyWriter

    rng = np.random.default_rng(seed)
    wo, wt = NpyWriter(d / "output.npy", n, np.float32), NpyWriter(d / "temperature.npy", n,
                                                                    np.float32)
    walk = 0.0
    for a in range(0, n, block):
        k = np.arange(a, min(a + block, n), dtype=np.float64)
        T = 10.0 + 50.0 * np.sin(2 * np.pi * k / 3.6e7)
        Tp = (T - 10.0) / 50.0
        bias = 0.5 + 0.3 * Tp + 0.02 * Tp ** 2 - 0.01 * Tp ** 3
        steps = 1e-3 * rng.standard_normal(k.size)
        rw = walk + np.cumsum(steps)
        walk = float(rw[-1])
        wo.write(bias + rng.standard_normal(k.size) + rw)
        wt.write(T)
    wo.close()
    wt.close()
    (d / "meta.json").write_text(json.dumps({"unit": "deg/h", "sample_rate": 100.0}))
    (d / "fit.json").write_text(json.dumps(bias_t_fit()))


_CHILD = r"""
import json, os, sys, time
def hwm():
    for line in open("/proc/self/status"):
        if line.startswith("VmHWM"):
            return int(line.split()[1]) / 1024
d, out = sys.argv[1], sys.argv[2]
t0 = time.perf_counter()
from fogbayes.stream import compensate_stream, stream_allan
res = {"import_MB": hwm(), "import_s": time.perf_counter() - t0}
t0 = time.perf_counter()
r = stream_allan(d, taus="octave", grid="index", rows=1 << 20)
res.update(adev_s=time.perf_counter() - t0, adev_MB=hwm(), adev_levels=len(r.m),
           adev_skipped=len(r.skipped), adev_buffers_MB=r.memory_bytes / 2**20,
           adev_tau=r.tau.tolist(), adev_dev=r.dev.tolist())
t0 = time.perf_counter()
c = compensate_stream(d, json.load(open(os.path.join(d, "fit.json"))), out, rows=1 << 20,
                      include_time=False)
res.update(comp_s=time.perf_counter() - t0, comp_MB=hwm(), passes=c.passes,
           iterations=c.iterations, outliers=c.outliers)
print(json.dumps(res))
"""


def run_child(d: Path, out: Path) -> dict:
    args = [sys.executable, "-c", _CHILD, str(d), str(out)]
    p = subprocess.run(args, capture_output=True, text=True, check=True)
    return json.loads(p.stdout.strip().splitlines()[-1])


def prefix_equality(d: Path, work: Path, n: int) -> dict:
    """Streaming vs in-memory on the first n samples (their own files)."""
    from fogbayes.data import Recording
    from fogbayes.stats.allan_kernels import allan_variance
    from fogbayes.stats.taus import cluster_sizes
    from fogbayes.stream import compensate_stream, stream_allan
    from fogbayes.thermal.workflow import compensate_recording

    pre = work / "prefix"
    pre.mkdir(parents=True, exist_ok=True)
    cols = {nm: np.load(d / f"{nm}.npy", mmap_mode="r")[:n].astype(np.float64)
            for nm in ("output", "temperature")}
    for nm, a in cols.items():
        np.save(pre / f"{nm}.npy", a)
    fit = json.loads((d / "fit.json").read_text())
    r = stream_allan(pre, taus="octave", grid="index", fs=100.0, unit=None)
    ms = cluster_sizes(n, "octave")
    ref = np.asarray(allan_variance(cols["output"], ms)[0])
    rec = Recording(time=np.arange(n) / 100.0, output=cols["output"],
                    temperatures=cols["temperature"])
    mem = compensate_recording(rec, fit)
    c = compensate_stream(pre, fit, work / "prefix_out", include_time=False)
    out = np.load(work / "prefix_out" / "output.npy")
    flags = np.load(work / "prefix_out" / "outlier.npy")
    return {"n": n, "adev_max_rel_diff": float(np.max(np.abs(r.var / ref - 1))),
            "output_bit_identical": bool(np.array_equal(out, mem["output"])),
            "flags_identical": bool(np.array_equal(flags, mem["outlier"])),
            "outliers": int(c.outliers)}


def large(args) -> dict:
    base = Path(args.dir)
    sizes = [int(float(s)) for s in args.sizes]
    need = sum(17 * n for n in sizes) * 1.05
    free = shutil.disk_usage(base.parent if not base.exists() else base).free
    out = {**header(), "disk_free_GB": free / 1e9, "disk_needed_GB": need / 1e9, "runs": []}
    if need > free - 10e9:  # leave 10 GB for everyone else
        raise SystemExit(f"needs {need / 1e9:.0f} GB of disk, {free / 1e9:.0f} GB free: use "
                         "smaller --sizes")
    for n in sizes:
        d = base / f"rec_{n:.0e}"
        t0 = time.perf_counter()
        make_record(d, n)
        made = time.perf_counter() - t0
        res = run_child(d, base / f"out_{n:.0e}")
        res.update(n=n, make_s=made, file_GB=8 * n / 1e9,
                   adev_Msamples_s=n / res["adev_s"] / 1e6,
                   comp_Msamples_s=n / res["comp_s"] / 1e6,
                   # every pass reads 8 bytes per sample; the last one writes 9 more
                   comp_GB_moved=(8 * res["passes"] + 9) * n / 1e9)
        res["comp_GB_s"] = res["comp_GB_moved"] / res["comp_s"]
        print(json.dumps({k: v for k, v in res.items() if not k.startswith("adev_tau")
                          and k != "adev_dev"}), flush=True)
        out["runs"].append(res)
        if n == sizes[0]:
            out["prefix"] = prefix_equality(d, base, min(args.prefix, n))
            print(json.dumps(out["prefix"]), flush=True)
        if not args.keep:
            shutil.rmtree(d)
            shutil.rmtree(base / f"out_{n:.0e}", ignore_errors=True)
    if not args.keep:
        shutil.rmtree(base, ignore_errors=True)
    return out


# ---------------------------------------------------------------------------- roofline
def roofline(args) -> dict:
    import jax

    from fogbayes.thermal.compensate import _xla_programs, bias_compensator
    from fogbayes.composite.compensate import build_compensator, compensate_numpy
    from fogbayes.composite.model import PAPER_000, Scaling, from_raw, raw_predict
    from fogbayes.thermal.model import ThermalSpec, bias_t_spec, thermal_basis
    from fogbayes.models.polynomial import design

    n, c, rep = args.n, args.chunk, args.repeat
    rng = np.random.default_rng(0)
    res = {**header(), "n": n, "chunk": c, "cases": {}}

    def copy_gbs(nbytes: int) -> float:
        src = np.ones(nbytes // 16)  # a copy reads and writes: moves 2 x its size
        dst = np.zeros_like(src)
        return 2 * src.nbytes / best_of(lambda: np.copyto(dst, src), rep) / 1e9

    T = rng.uniform(-40, 60, n)
    R = rng.normal(size=n)
    y = rng.normal(size=n)
    out = np.empty(n)
    for label, spec, z in (("bias-t cubic", bias_t_spec(3), T[:, None]),
                           ("thermal (2,2)", ThermalSpec(2, 2), np.column_stack([T, R]))):
        basis = thermal_basis(spec, z[:1000])
        coef = 0.1 * np.arange(1, basis.n_terms + 1)
        bpp = 8 * (2 + z.shape[1])
        row = {"bytes_per_sample": bpp, "copy_GB_s": copy_gbs(bpp * n)}
        # "library": the library's compensator (on a CPU the compiled loop, writing each
        # chunk in place); "xla": the term set's XLA program, the library's path where JAX
        # sees a GPU, here on the CPU (the one implementation the loop would be replaced
        # by); "matrix" the former XLA form y - X(z) @ coef
        matrix = jax.jit(lambda coef, z, y, basis=basis: y - design(z, basis) @ coef)
        centre, scale = np.asarray(basis.centre), np.asarray(basis.scale)
        xla = (lambda coef, z, y, f=_xla_programs(basis.terms)[0], centre=centre,
               scale=scale: f(coef, z, y, centre, scale))
        in_place = jax.default_backend() == "cpu"
        for name, f in (("library", bias_compensator(basis).single), ("xla", xla),
                        ("matrix", matrix)):
            def run(f=f, coef=coef, z=z, into=in_place and name == "library"):
                for a in range(0, n, c):
                    if into:  # the loop, as the stream asks for it (chunks below
                        # NUMPY_BELOW would otherwise take the one-off NumPy path)
                        f(coef, z[a:a + c], y[a:a + c], out=out[a:a + c], method="loop")
                    else:
                        out[a:a + c] = f(coef, z[a:a + c], y[a:a + c])
            run()
            row[name + "_GB_s"] = bpp * n / best_of(run, rep) / 1e9

        def numpy_run(z=z, basis=basis, coef=coef):
            zs = (z - np.asarray(basis.centre)) / np.asarray(basis.scale)
            acc = np.zeros(n)
            for k, e in enumerate(basis.terms):
                col = np.ones(n)
                for j, ej in enumerate(e):
                    for _ in range(ej):  # repeated products: x ** 3 would call pow
                        col = col * zs[:, j]
                acc += coef[k] * col
            np.subtract(y, acc, out=out)
        row["numpy_GB_s"] = bpp * n / best_of(numpy_run, max(1, rep // 2)) / 1e9
        for k in ("library", "xla", "matrix", "numpy"):
            row[k + "_vs_copy"] = row[k + "_GB_s"] / row["copy_GB_s"]
        res["cases"][label] = row
        print(label, json.dumps(row), flush=True)
    # composite: Halley (reads U, T, t; writes the rate: in place on a CPU, into U's
    # donated buffer under XLA)
    Tc, W, tc = rng.uniform(-30, 60, n), rng.uniform(-80, 80, n), rng.uniform(0, 60, n)
    U = raw_predict(PAPER_000, Tc, W, tc)
    sc = Scaling(15.0, 45.0, 80.0, 60.0, float(U.mean()), float(np.abs(U - U.mean()).max()))
    comp = build_compensator(from_raw(PAPER_000, sc), sc, T_range=(-30, 60), W_range=(-80, 80))
    row = {"bytes_per_sample": 32, "copy_GB_s": copy_gbs(32 * n)}

    def comp_run():  # CPU: the compiled loop writes each chunk in place; else XLA, U donated
        for a in range(0, n, c):
            if comp.loop is not None:
                comp.stream(U[a:a + c], Tc[a:a + c], tc[a:a + c], out=out[a:a + c])
            else:
                out[a:a + c] = comp.stream(jax.device_put(U[a:a + c]), Tc[a:a + c],
                                           tc[a:a + c])
    comp_run()
    row["library_GB_s"] = 32 * n / best_of(comp_run, rep) / 1e9
    # the same compensator's XLA program (host=False: what a GPU machine runs), on the CPU
    xla_comp = build_compensator(from_raw(PAPER_000, sc), sc, T_range=(-30, 60),
                                 W_range=(-80, 80), host=False)

    def xla_run():
        for a in range(0, n, c):
            out[a:a + c] = xla_comp.stream(jax.device_put(U[a:a + c]), Tc[a:a + c], tc[a:a + c])
    xla_run()
    row["xla_GB_s"] = 32 * n / best_of(xla_run, rep) / 1e9
    m = min(n, 2_000_000)
    p = from_raw(PAPER_000, sc)
    row["numpy_GB_s"] = 32 * m / best_of(lambda: compensate_numpy(
        p, sc, comp.box, U[:m], Tc[:m], tc[:m], iterations=comp.iterations), 1) / 1e9
    for k in ("library", "xla", "numpy"):
        row[k + "_vs_copy"] = row[k + "_GB_s"] / row["copy_GB_s"]
    res["cases"]["composite halley"] = row
    print("composite halley", json.dumps(row), flush=True)
    res["end_to_end"] = end_to_end(args)
    return res


def end_to_end(args) -> dict:
    """compensate_stream from a page-cached .npy directory to a new one, no flags, bytes/s
    (1 MiB-row chunks, compensator pieces of 2^18 rows; compile excluded)."""
    from fogbayes.stream import compensate_stream

    n = args.n
    d = Path(args.dir) / "e2e"
    make_record(d, n)
    fit = json.loads((d / "fit.json").read_text())
    for f in ("output.npy", "temperature.npy"):
        (d / f).read_bytes()  # into the page cache
    src = np.ones(17 * n // 16)  # 8 bytes read + 9 written per sample
    dst = np.zeros_like(src)
    copy = 2 * src.nbytes / best_of(lambda: np.copyto(dst, src), args.repeat) / 1e9
    row = {"bytes_per_sample": 17, "copy_GB_s": copy}
    times = []
    for r in range(4):  # a fresh output each time: overwriting would time the truncation
        target = d.parent / f"e2e_out{r}"
        t0 = time.perf_counter()
        compensate_stream(d, fit, target, rows=1 << 20, flags=False, include_time=False)
        times.append(time.perf_counter() - t0)
        shutil.rmtree(target)
    row["library_GB_s"] = 17 * n / min(times[1:]) / 1e9
    row["library_vs_copy"] = row["library_GB_s"] / copy
    shutil.rmtree(d.parent, ignore_errors=True)
    print("end to end", json.dumps(row), flush=True)
    return row


# --------------------------------------------------------------------------------- adev
def adev(args) -> dict:
    import allantools
    import jax

    from fogbayes.stats.allan_kernels import allan_variance
    from fogbayes.stats.taus import cluster_sizes
    from fogbayes.stream import allan_variance_fast

    n = int(float(args.n))
    rng = np.random.default_rng(0)
    y = 400.0 + rng.normal(size=n) + 0.01 * np.cumsum(rng.normal(size=n))
    out = {**header(), "allantools": allantools.__version__, "n": n, "cases": []}
    for grid in ("octave", "dense"):
        ms = cluster_sizes(n, grid)
        taus = np.asarray(ms, float) / 100.0

        def theirs(taus=taus):
            return allantools.oadev(y, rate=100.0, data_type="freq", taus=taus)[1] ** 2

        def stats(ms=ms):
            return np.asarray(jax.block_until_ready(allan_variance(y, ms)[0]))

        def fast(ms=ms):
            return allan_variance_fast(y, ms)[0]
        ref = theirs()
        stats()  # compile
        row = {"grid": grid, "taus": len(ms)}
        for name, fn in (("allantools", theirs), ("fogbayes.stats", stats), ("stream.fast", fast)):
            row[name + "_s"] = best_of(fn, args.repeat if name != "allantools" else
                                       max(1, args.repeat - 1))
            row[name + "_max_rel_diff"] = float(np.max(np.abs(fn() / ref - 1)))
        for name in ("fogbayes.stats", "stream.fast"):
            row[name + "_ratio"] = row["allantools_s"] / row[name + "_s"]
        row["load_after"] = os.getloadavg()
        out["cases"].append(row)
        print(json.dumps(row), flush=True)
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("what", choices=("large", "roofline", "adev"))
    ap.add_argument("--sizes", nargs="+", default=["2e8", "2e9"])
    ap.add_argument("--dir", default="/tmp/fogbayes_stream")
    ap.add_argument("--prefix", type=int, default=20_000_000)
    ap.add_argument("--keep", action="store_true")
    ap.add_argument("--n", type=float, default=None)
    ap.add_argument("--chunk", type=int, default=1 << 18)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--json", default=None, help="also write the results here")
    args = ap.parse_args()
    if args.what == "roofline":
        args.n = int(args.n or 1 << 24)
        res = roofline(args)
    elif args.what == "adev":
        args.n = args.n or 1e7
        res = adev(args)
    else:
        res = large(args)
    text = json.dumps(res, indent=1)
    if args.json:
        Path(args.json).write_text(text)
    print(text)


if __name__ == "__main__":
    main()
