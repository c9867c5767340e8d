"""Streaming (fogbayes.stream): identical results to the in-memory paths, bounded memory.

References: the in-memory workflows (compensate_recording), fogbayes.stats.allan_variance,
allantools, a long-double Allan variance, numpy's median and the in-memory Pauta rule. The
peak-RSS test runs the streaming path in a subprocess on two files 10x apart.
"""

from __future__ import annotations

import itertools
import json
import os
import subprocess
import sys
import warnings

import jax
import numpy as np
import pytest

from fogbayes.data import Recording, load, save
from fogbayes.data.recording import Metadata
from fogbayes.errors import (
    FileFormatError,
    FogbayesError,
    ImplausibleValueError,
    MissingColumnError,
    NonFiniteError,
    NonNumericError,
    ShapeError,
    TimeOrderError,
)
from fogbayes.preprocess import pauta_flags
from fogbayes.preprocess._checks import segment_bounds
from fogbayes.stats.allan_kernels import allan_variance
from fogbayes.stats.taus import cluster_sizes
from fogbayes.stream import (
    allan_variance_fast,
    compensate_stream,
    open_source,
    scan_time,
    stream_allan,
)
from fogbayes.stream.allan import GridError
from fogbayes.stats.allan_accumulators import OctaveAccumulator, PhaseAccumulator, variance
from fogbayes.stream.pauta import stream_pauta


def _read(path, names):
    path = str(path)
    if path.endswith(".parquet"):
        import pyarrow.parquet as pq

        tb = pq.read_table(path)
        return {k: tb.column(k).to_numpy() for k in names}
    if path.endswith(".npz"):
        with np.load(path) as z:
            return {k: z[k] for k in names}
    return {k: np.load(os.path.join(path, f"{k}.npy")) for k in names}


def _series(n, seed=0):
    """Offset + white + random-walk rate: the phase wanders far from zero (a hard case)."""
    rng = np.random.default_rng(seed)
    return 400.0 + rng.normal(size=n) + 0.01 * np.cumsum(rng.normal(size=n))


# ------------------------------------------------------------------------------ sources
@pytest.fixture(scope="module")
def rec():
    n = 5003
    rng = np.random.default_rng(1)
    return Recording(time=10.0 + 0.1 * np.arange(n), output=rng.normal(size=n), unit="deg/s",
                     temperatures=np.column_stack([20 + 1e-3 * np.arange(n), np.full(n, 21.0)]),
                     temperature_names=("temperature", "temperature_2"),
                     input_rate=np.zeros(n), meta=Metadata(sensor_id="s1", sample_rate=10.0))


@pytest.mark.parametrize("ext", ["npz", "parquet"])
def test_sources_give_back_the_saved_recording(rec, tmp_path, ext):
    src = open_source(save(rec, tmp_path / f"r.{ext}"))
    assert (src.n, src.unit, src.sample_rate, src.sensor_id) == (rec.n, "deg/s", 10.0, "s1")
    assert src.temperature_names == ("temperature", "temperature_2")
    parts = list(src.chunks(999))
    assert [c.n for c in parts] == [999] * 5 + [8] and parts[-1].start == 4995
    for field, ref in (("time", rec.time), ("output", rec.output),
                       ("temperatures", rec.temperatures), ("input_rate", rec.input_rate)):
        assert np.array_equal(np.concatenate([getattr(c, field) for c in parts]), ref)


def test_npy_layouts_and_compressed_npz(rec, tmp_path):
    np.savez_compressed(tmp_path / "c.npz", time=rec.time, output=rec.output)
    got = np.concatenate([c.output for c in open_source(tmp_path / "c.npz").chunks(700)])
    assert np.array_equal(got, rec.output)
    d = tmp_path / "cols"
    d.mkdir()
    np.save(d / "time.npy", rec.time)
    np.save(d / "output.npy", rec.output.astype(">f4"))  # big-endian float32 is converted
    np.save(d / "temperature.npy", rec.temperatures[:, 0])
    src = open_source(d)
    assert src.kind == "npy-dir" and src.temperature_names == ("temperature",)
    got = np.concatenate([c.output for c in src.chunks(4096)])
    assert np.array_equal(got, rec.output.astype(np.float32).astype(float))
    st = np.zeros(rec.n, dtype=[("time", "<f8"), ("output", "<f8")])
    st["time"], st["output"] = rec.time, rec.output
    np.save(tmp_path / "s.npy", st)
    got = np.concatenate([c.output for c in open_source(tmp_path / "s.npy").chunks(333)])
    assert np.array_equal(got, rec.output)
    np.save(tmp_path / "plain.npy", rec.output)
    assert open_source(tmp_path / "plain.npy").columns == ("output",)


def _bad_files(tmp, rec):
    t, y = rec.time.copy(), rec.output.copy()
    np.savez(tmp / "miss.npz", time=t, outptu=y)
    import pyarrow as pa
    import pyarrow.parquet as pq

    pq.write_table(pa.table({"time": t, "output": y.astype(str)}), tmp / "text.parquet")
    np.savez(tmp / "twod.npz", time=t, output=np.column_stack([y, y]))
    tn = t.copy()
    tn[2500] = np.nan
    np.savez(tmp / "nan.npz", time=tn, output=y)
    tb = t.copy()
    tb[1000] = tb[999]  # a repeated time stamp exactly at a chunk boundary (chunks of 1000)
    np.savez(tmp / "back.npz", time=tb, output=y)
    (tmp / "ragged").mkdir()
    np.save(tmp / "ragged" / "time.npy", t)
    np.save(tmp / "ragged" / "output.npy", y[:-1])
    np.save(tmp / "trunc.npy", y)
    with open(tmp / "trunc.npy", "r+b") as fh:
        fh.truncate(os.path.getsize(tmp / "trunc.npy") - 80)
    (tmp / "x.csv").write_text("time,output\n0,1\n")


@pytest.mark.parametrize("name,err,where", [
    ("miss.npz", MissingColumnError, "did you mean 'outptu'"),
    ("text.parquet", NonNumericError, "column 'output'"),
    ("twod.npz", FileFormatError, "expected 1-D"),
    ("nan.npz", NonFiniteError, "row 2500"),
    ("back.npz", TimeOrderError, "row 1000"),
    ("ragged", ShapeError, "column 'output'"),
    ("trunc.npy", FileFormatError, "ends early"),
    ("x.csv", FileFormatError, "cannot stream"),
])
def test_bad_files_raise_errors_naming_file_column_row(rec, tmp_path, name, err, where):
    _bad_files(tmp_path, rec)
    with pytest.raises(err) as info:
        src = open_source(tmp_path / name)
        for _ in src.chunks(1000, fields=("output",) if name == "trunc.npy" else ("time", "output")):
            pass
    assert name in str(info.value) and where in str(info.value)


def _lab_file(tmp, rec, temperature):
    """``rec`` as a lab logs it: time in ms, the temperature as raw words (T = w/100 - 20)."""
    path = tmp / "lab.npz"
    np.savez(path, time=1e3 * rec.time, output=rec.output, temperature=temperature)
    return path


def test_sources_read_lab_units_as_the_in_memory_loader_does(rec, tmp_path):
    path = _lab_file(tmp_path, rec, 100.0 * (rec.temperatures[:, 0] + 20.0))
    units = dict(time_unit="ms", temperature_scale=0.01, temperature_offset=-20.0)
    ref = load(path, **units)  # the in-memory reader: the reference
    parts = list(open_source(path, **units).chunks(1000))
    for field, want in (("time", ref.time), ("output", ref.output),
                        ("temperatures", ref.temperatures)):
        np.testing.assert_array_equal(np.concatenate([getattr(c, field) for c in parts]), want)
    np.testing.assert_allclose(ref.time, rec.time, rtol=1e-15)
    np.testing.assert_allclose(ref.temperatures[:, 0], rec.temperatures[:, 0], atol=1e-12)


def test_sources_refuse_raw_words_and_milliseconds_read_as_degrees_and_seconds(rec, tmp_path):
    words = 100.0 * (rec.temperatures[:, 0] + 20.0)
    words[:3100] = 25.0  # plausible as deg C until row 3100 (the fourth chunk of 1000)
    path = _lab_file(tmp_path, rec, words)
    with pytest.raises(ImplausibleValueError) as info:
        for _ in open_source(path, time_unit="ms").chunks(1000):
            pass
    msg = str(info.value)
    assert "lab.npz" in msg and "temperature" in msg and "row 3100" in msg
    # 10 Hz stamped in microseconds and read as seconds: 1e-5 Hz, below the plausible 1e-4
    # (in ms it would be 0.01 Hz, which the rule cannot tell from a slow logger)
    np.savez(tmp_path / "us.npz", time=1e6 * rec.time, output=rec.output)
    with pytest.raises(ImplausibleValueError, match="not in seconds.*--time-unit"):
        next(open_source(tmp_path / "us.npz").chunks(1000))
    assert next(open_source(tmp_path / "us.npz", time_unit="us").chunks(1000)).n == 1000


# --------------------------------------------------------------------------------- scan
@pytest.mark.parametrize("case", ["float_grid", "exact_grid", "jitter_gaps", "even_count"])
def test_scan_median_and_runs_equal_numpy(tmp_path, case):
    rng = np.random.default_rng(3)
    t = {"float_grid": 1.7e9 + 0.1 * np.arange(20001),
         "exact_grid": 0.5 * np.arange(3000),
         "jitter_gaps": np.cumsum(0.01 * (1 + 1e-3 * rng.normal(size=20001))),
         "even_count": np.cumsum(rng.uniform(0.5, 1.5, size=1001))}[case]
    if case == "jitter_gaps":
        t[5000:] += 3.0
        t[12000:] += 0.05
    np.savez(tmp_path / "t.npz", time=t, output=np.zeros(t.size))
    s = scan_time(open_source(tmp_path / "t.npz"), rows=777)
    assert s.dt_median == np.median(np.diff(t))  # exact, not approximately
    assert np.array_equal(s.bounds, segment_bounds(t))
    b = segment_bounds(t)
    means = [np.diff(t[a:c]).mean() for a, c in itertools.pairwise(b)]
    # compensated sums vs numpy's pairwise mean: both within a few ulp of the exact mean
    assert np.allclose(s.run_dt_mean, means, rtol=1e-14, atol=0)


# ------------------------------------------------------------------------- Allan variance
def _long_double_avar(y, ms):
    S = np.concatenate([[0], np.cumsum(y.astype(np.longdouble))])
    out = []
    for m in ms:
        d = S[2 * m:] - 2 * S[m:-m] + S[:-2 * m]
        out.append(float(np.sum(d * d) / (2 * m * m * d.size)))
    return np.array(out)


@pytest.mark.parametrize("feed,chunk", [(999, 1024), (4096, 4096), (20001, 256)])
def test_accumulators_match_in_memory_and_allantools(feed, chunk):
    import allantools

    n = 20001  # odd: no chunk size divides it; chunk 256 < 2 m_max = 8192
    y = _series(n)
    for grid in ("octave", (1, 3, 10, 37, 100, 333, 1000, 3333)):
        ms = cluster_sizes(n, grid) if grid == "octave" else grid
        ref = np.asarray(allan_variance(y, ms)[0])
        at = allantools.oadev(y, rate=1.0, data_type="freq", taus=np.asarray(ms, float))[1] ** 2
        accs = [PhaseAccumulator(ms, chunk=chunk)]
        if grid == "octave":
            accs.append(OctaveAccumulator(len(ms), chunk=chunk))
        for acc in accs:
            for a in range(0, n, feed):
                acc.update(y[a:a + feed])
            var = variance(ms, *acc.result())
            # fogbayes and allantools difference prefix sums of a phase that wanders to
            # ~1e3 here: their own rounding is ~1e-12 relative; 1e-10 is the bound
            assert np.max(np.abs(var / ref - 1)) < 1e-10
            assert np.max(np.abs(var / at - 1)) < 1e-10
            assert np.array_equal(acc.result()[1], n - 2 * np.asarray(ms, float) + 1)


def test_accumulators_are_accurate_against_long_double():
    y = 1e4 + _series(200_000, seed=2) + 1e-5 * np.arange(200_000)  # offset and drift
    ms = cluster_sizes(y.size, "octave")
    ref = _long_double_avar(y, ms)
    for acc in (OctaveAccumulator(len(ms), chunk=4096), PhaseAccumulator(ms, chunk=4096)):
        acc.update(y)
        # long double (64-bit mantissa) is ~2000x finer than float64; measured 4e-15 (pyramid)
        # and 3e-13 (phase window)
        assert np.max(np.abs(variance(ms, *acc.result()) / ref - 1)) < 1e-11


def test_gaps_are_excluded_like_in_memory():
    rng = np.random.default_rng(4)
    y = rng.normal(size=30000)
    y[[5, 700, 701, 20000]] = np.nan
    y[25000:25100] = np.nan
    ms = (1, 2, 4, 8, 64, 512, 2048)
    ref, count = (np.asarray(a) for a in allan_variance(y, ms, gaps=True))
    var, cnt = allan_variance_fast(y, ms, chunk=1024)
    assert np.array_equal(cnt, count)
    assert np.max(np.abs(var / ref - 1)) < 1e-12  # same terms; rounding only
    var, cnt = allan_variance_fast(y, (3, 5, 700), chunk=512)  # the phase path
    ref, count = (np.asarray(a) for a in allan_variance(y, (3, 5, 700), gaps=True))
    assert np.array_equal(cnt, count) and np.max(np.abs(var / ref - 1)) < 1e-12
    with pytest.raises(FogbayesError, match="inf"):
        allan_variance_fast(np.r_[1.0, np.inf, 1.0, 2.0], (1,))


def test_fast_allan_batch_equals_rows():
    Y = np.stack([_series(8192, seed=s) for s in range(3)])
    ms = cluster_sizes(8192, "octave")
    var, _ = allan_variance_fast(Y, ms)
    ref = np.asarray(allan_variance(Y, ms)[0])
    assert var.shape == (3, len(ms)) and np.max(np.abs(var / ref - 1)) < 1e-10


@pytest.mark.parametrize("ext", ["parquet", "npz"])
def test_stream_allan_equals_the_workflow_on_a_gappy_record(tmp_path, ext):
    from fogbayes.allan.workflow import uniform_rate

    n = 30011
    t = 1000.0 + 0.01 * np.arange(n)
    keep = np.ones(n, bool)
    keep[[100, 101, 5000]] = False
    keep[20000:20500] = False  # a 5 s gap
    y = 0.3 + 0.01 * _series(n, seed=5)
    rec = Recording(time=t[keep], output=y[keep], unit="deg/s")  # no sample rate: scanned
    path = save(rec, tmp_path / f"g.{ext}")
    yy, fs, missing = uniform_rate(rec)  # the workflow's grid: gaps become NaN
    for taus, rows in (("octave", 999), ((1, 3, 10, 30, 100, 300, 1000, 3000), 4096)):
        ms = cluster_sizes(yy.size, taus) if taus == "octave" else taus
        ref, count = (np.asarray(a) for a in allan_variance(yy, ms, gaps=True))
        r = stream_allan(path, taus=taus, rows=rows, chunk=1024)
        assert (r.fs, r.n, r.n_missing, r.unit) == (fs, yy.size, missing, "deg/h")
        assert np.array_equal(r.n_terms, count)
        assert np.max(np.abs(r.var / ref - 1)) < 1e-10


def test_max_lag_bounds_memory_and_off_grid_times_fail(tmp_path):
    mem = []
    for n in (20_000, 200_000):
        np.save(tmp_path / f"y{n}.npy", _series(n))
        r = stream_allan(tmp_path / f"y{n}.npy", fs=10.0, grid="index", max_lag=256,
                         chunk=1024)
        assert r.m[-1] == 256 and min(r.skipped) == 512
        mem.append(r.memory_bytes)
    assert mem[0] == mem[1]  # the buffers depend on max_lag and chunk, not on n
    with pytest.raises(FogbayesError, match="max_lag"):
        stream_allan(tmp_path / "y20000.npy", fs=10.0, grid="index", taus=(1024,), max_lag=8)
    t = np.arange(100.0)
    t[50] += 0.3
    np.savez(tmp_path / "off.npz", time=t, output=np.zeros(100))
    with pytest.raises(GridError, match="row 50"):
        stream_allan(tmp_path / "off.npz", fs=1.0)


# ------------------------------------------------------------------------- compensation
@pytest.fixture(scope="module")
def thermal_run(tmp_path_factory):
    from fogbayes.simulate import simulate

    rec = simulate("paper004", seed=3, soak=1200.0, ramp_rate=2.0).recording  # 3 h at 1 Hz
    part = rec.slice(1000, 5000)  # compensated: a soak, a ramp and the next soak
    return rec, part, save(part, tmp_path_factory.mktemp("th") / "run.npz")


@pytest.mark.parametrize("model,opts,rows,out", [
    ("bias-t", {}, 997, "o.parquet"),
    ("thermal", {}, 37, "odir"),          # rows < Savitzky-Golay halo (61 samples)
    ("thermal", {}, 4096, "o.npz"),
    ("thermal", {"processing": "paper"}, 333, "o.parquet"),  # block differences, held
    ("thermal", {"rate_method": "difference"}, 2000, "odir"),  # block differences, interp
])
def test_thermal_compensation_is_bit_identical(thermal_run, tmp_path, model, opts, rows, out):
    from fogbayes.thermal.workflow import compensate_recording, fit_recording

    rec, part, path = thermal_run
    fit = fit_recording(rec, model=model, **opts)
    ref = compensate_recording(part, fit)
    res = compensate_stream(path, fit, tmp_path / out, rows=rows)
    got = _read(res.path, ("time", "output", "outlier"))
    for k in ("time", "output", "outlier"):
        if k == "output" and jax.default_backend() != "cpu":
            # on a GPU the in-memory path is XLA there, the stream the host loop: not bit
            # for bit (H200, 2026-11-28); the GPU compensator agrees with NumPy to 1.8e-15
            # deg/h (benchmarks/RESULTS_gpu.md), so 1e-12 leaves room for the covariates
            np.testing.assert_allclose(got[k], ref[k], rtol=0, atol=1e-12)
            continue
        assert np.array_equal(got[k], ref[k]), k  # same operations, same order: exact
    assert res.outliers == int(ref["outlier"].sum())
    if model == "thermal" and not opts:
        assert ref["outlier"].sum() > 0 and res.iterations >= 2  # the flags were exercised


def test_fused_compensator_equals_the_design_matrix_formula(thermal_run):
    # the library compensator sums the polynomial term by term (fused by XLA); the
    # reference is the textbook y - X(z) @ coef built in NumPy. Different summation order
    # and 1/scale: a couple of roundings per term. The terms (|coef_k| times scaled
    # monomials, |.| <= 1 in range) cancel to a small bias, so the yardstick is their sum:
    # bound 2 p eps (|y| + sum |coef|) ~ 2e-14 deg/h; measured 2.7e-15
    from fogbayes.thermal.compensate import compensate_bias
    from fogbayes.models.basis_document import basis_from_dict
    from fogbayes.models.polynomial import design
    from fogbayes.thermal.workflow import fit_recording

    rec, part, _ = thermal_run
    fit = fit_recording(rec, model="thermal")
    basis, coef = basis_from_dict(fit["params"]["basis"]), np.asarray(fit["params"]["coef"])
    rng = np.random.default_rng(0)
    lo, hi = np.asarray(basis.centre) - basis.scale, np.asarray(basis.centre) + basis.scale
    z = rng.uniform(lo, hi, (5000, len(basis.names)))
    y = rng.normal(0.0, 5.0, 5000)
    ref = y - np.asarray(design(z, basis)) @ coef
    got = compensate_bias(coef, z, y, basis)
    tol = 2 * coef.size * np.finfo(float).eps * (np.abs(y) + np.abs(coef).sum())
    assert np.all(np.abs(got - ref) <= tol)
    assert np.max(np.abs(got - ref)) > 0 or coef.size == 1  # really a different summation


def test_long_savgol_window_agrees_to_fft_rounding(thermal_run, tmp_path):
    from fogbayes.thermal.workflow import compensate_recording, fit_recording

    rec, part, path = thermal_run
    fit = fit_recording(rec, model="thermal", rate_window_s=1000.0)  # 1001 samples: FFT path
    ref = compensate_recording(part, fit)
    res = compensate_stream(path, fit, tmp_path / "o", rows=2500)
    got = _read(res.path, ("output", "outlier"))
    # The FFT's rounding depends on the array it is given (the run vs the window): measured
    # 1e-12 deg/h on outputs of ~1 deg/h (the temperature-rate term is FFT-rounded to
    # ~1e-15 of the 100 deg C swing, times the coefficients). 1e-10 absolute leaves margin.
    assert np.max(np.abs(got["output"] - ref["output"])) < 1e-10
    assert np.array_equal(got["outlier"], ref["outlier"])


def test_composite_compensation_is_bit_identical(tmp_path):
    from fogbayes.simulate.scenarios import simulate
    from fogbayes.composite.workflow import compensate_recording, fit_recording

    warnings.filterwarnings("ignore")
    rec = simulate("paper000", seed=21, dwell=20.0).recording
    fit = fit_recording(rec, orders="2,3,2,2")
    for r, rows, out in ((rec, 997, "c.npz"), (rec.replace(input_rate=None), 1234, "c.parquet")):
        ref = compensate_recording(r, fit)
        res = compensate_stream(save(r, tmp_path / f"in_{out}"), fit, tmp_path / out, rows=rows)
        got = _read(res.path, ("time", "rate", "outlier"))
        assert np.array_equal(got["rate"], ref["rate"], equal_nan=True)
        assert np.array_equal(got["outlier"], ref["outlier"]) and np.array_equal(got["time"],
                                                                               ref["time"])


@pytest.mark.parametrize("max_iter", [1, 2, 100])
def test_pauta_stream_equals_in_memory(max_iter):
    rng = np.random.default_rng(6)
    x = rng.standard_t(3, size=20000)  # heavy tails: several iterations flag something
    ref = pauta_flags(x, max_iter=max_iter)
    got = stream_pauta(lambda: (x[a:a + 777] for a in range(0, x.size, 777)),
                       max_iter=max_iter)
    assert np.array_equal(got.flags(x), ref.mask)
    assert got.iterations == ref.iterations
    assert abs(got.threshold / ref.threshold - 1) < 1e-13  # merged moments vs numpy
    assert ref.count > 0


# ---------------------------------------------------------------------------- peak RSS
_CHILD = r"""
import json, os, sys
import numpy as np
def hwm():
    for line in open("/proc/self/status"):
        if line.startswith("VmHWM"):
            return int(line.split()[1]) / 1024
d = sys.argv[1]
from fogbayes.stream import compensate_stream, stream_allan
stream_allan(d, taus="octave", max_lag=1 << 16, grid="index", fs=10.0, rows=1 << 18)
compensate_stream(d, json.load(open(os.path.join(d, "fit.json"))), d + "_out",
                  rows=1 << 18, include_time=False)
out = {"stream": hwm()}
from fogbayes.stream import oadev_fast  # now the in-memory path in the same process
y = np.load(os.path.join(d, "output.npy")).astype(float)
T = np.load(os.path.join(d, "temperature.npy")).astype(float)
oadev_fast(y, 10.0, taus="octave", m_max=1 << 16)
out["memory"] = hwm()
print(json.dumps(out))
"""


def _rss_record(d, n):
    from fogbayes.models.basis_document import coefficient_document
    from fogbayes.thermal.model import bias_t_spec, thermal_basis
    from fogbayes.thermal.data import make_processing

    d.mkdir()
    rng = np.random.default_rng(0)
    T = (20 + 30 * np.sin(1e-6 * np.arange(n))).astype(np.float32)
    np.save(d / "temperature.npy", T)
    np.save(d / "output.npy", (0.5 + 0.01 * (T - 20) + rng.normal(size=n)).astype(np.float32))
    spec = bias_t_spec(2)
    basis = thermal_basis(spec, np.array([[-10.0], [50.0]]))
    doc = {"model": "bias-t", "processing": make_processing()._asdict(),
           "params": {"spec": spec._asdict(), **coefficient_document(
               basis, np.array([0.5, 0.3, 0.01]), valid_range={"T": (-10.0, 50.0)})}}
    (d / "fit.json").write_text(json.dumps(doc))


@pytest.mark.skipif(not os.path.exists("/proc/self/status"), reason="needs Linux /proc")
def test_peak_rss_does_not_grow_with_file_size(tmp_path):
    # glibc's dynamic mmap threshold lets freed chunk buffers stay in the heap, which moves
    # the peak by +-30 MB from run to run whatever the size (measured 366 / 358 / 362 MB at
    # 1e6 / 1e7 / 1e8 samples); a fixed threshold returns them, so the comparison below
    # measures the algorithm's memory and can be tight (322 / 322 MB with it).
    env = {**os.environ, "MALLOC_MMAP_THRESHOLD_": "131072"}
    peaks = {}
    for n in (1_000_000, 10_000_000):
        d = tmp_path / f"r{n}"
        _rss_record(d, n)
        out = subprocess.run([sys.executable, "-c", _CHILD, str(d)], capture_output=True,
                             text=True, timeout=300, check=True, env=env)
        peaks[n] = json.loads(out.stdout.strip().splitlines()[-1])
    small, big = peaks[1_000_000], peaks[10_000_000]
    # Streaming: the same chunk buffers and accumulators (max_lag fixed) for both sizes, so
    # the peak may differ only by allocator and JAX-runtime noise: 5 % of the ~320 MB peak
    # plus 16 MB (measured growth: 0-1 MB). The in-memory run in the same process holds the
    # record (9e6 more samples x 8 bytes x 2 float64 columns = 144 MB more), so this bound
    # would fail if the stream kept what it read (a memory map of the 2e7-sample float32
    # output column alone showed +69 MB).
    assert big["stream"] - small["stream"] < 0.05 * small["stream"] + 16
    assert big["memory"] - small["memory"] > 100
