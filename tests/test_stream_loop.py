"""Streaming a loop calibration (``compensate --stream -p loop.json``) equals the in-memory
``apply_calibration`` on the same record, at any chunk size.

Reference: :func:`fogbayes.loop.calibration.apply_calibration` (every sample in memory) and
``np.median`` for the exact streamed medians. The record exercises every whole-record
computation: planted spikes (the flags' median and MAD), two temperature channels on a
lagged chamber programme with corners (block means, Savitzky-Golay dT/dt, corner fits),
filters with memory (first-order lag, play operator), a warm-up from the first sample, and
run events left out or applied. Tolerances: flags equal; outputs to 1e-9 deg/h (the lag's
recursion restarts from the carried value, a rounding-level difference; the composite
solver's tolerance is 1e-6 of full scale, so its rates are compared to 1e-7 deg/s).
"""

from __future__ import annotations

import json

import numpy as np
import pytest

import fogbayes.cli as cli
from fogbayes.data import Recording, load, save
from fogbayes.data.doc_rules import LOOP_SCHEMA
from fogbayes.loop.calibration import apply_calibration
from fogbayes.stream.loop_calibration import compensate_loop_stream
from fogbayes.stream.select import stream_median

FS, HOURS = 2.0, 1.5


def _chamber(t):
    """A lagged two-level programme with ramps (corners in dT/dt), deg C."""
    prog = np.interp(t, [0, 600, 1800, 2700, 3900, 5400], [20, 20, 60, 60, -10, -10])
    a = np.exp(-1.0 / FS / 200.0)
    T = np.empty_like(prog)
    T[0] = prog[0]
    for i in range(1, prog.size):
        T[i] = a * T[i - 1] + (1 - a) * prog[i]
    return T


@pytest.fixture(scope="module")
def record(tmp_path_factory):
    rng = np.random.default_rng(7)
    t = 1000.0 + np.arange(int(HOURS * 3600 * FS)) / FS
    T1 = _chamber(t - t[0]) + 0.01 * rng.standard_normal(t.size)
    T2 = T1 + 0.4 * np.sin(2 * np.pi * (t - t[0]) / 3000.0)
    W = np.repeat([0.0, 10.0, -10.0, 50.0, -50.0, 100.0], -(-t.size // 6))[:t.size]
    y = 0.5 + 0.01 * (T1 - 20) + 0.05 * rng.standard_normal(t.size)
    y[[100, 5000, 9001]] += [30.0, -25.0, 40.0]  # isolated spikes
    rec = Recording(time=t, output=y, unit="deg/h", temperatures=np.column_stack([T1, T2]),
                    temperature_names=("T_case", "T_fibre"), input_rate=W)
    d = tmp_path_factory.mktemp("stream_loop")
    save(rec, d / "rec.npz")
    return d, rec


def _doc(family: str) -> dict:
    sensor = [
        {"kind": "intercept", "params": {}},
        {"kind": "tpoly", "params": {"channel": 0, "powers": [1, 2], "centre": 20.0,
                                     "scale": 40.0}},
        {"kind": "rate", "params": {"scale": 1.0}},
        {"kind": "gradient", "params": {"a": 0, "b": 1, "scale": 1.0}},
        {"kind": "hysteresis", "params": {"r0": 0.05}},
        {"kind": "play", "params": {"channel": 0, "width": 2.0}},
        {"kind": "lag", "params": {"channel": 1, "tau": 300.0, "centre": 20.0, "scale": 40.0}},
        {"kind": "drift_exp", "params": {"tau": 600.0}},
        {"kind": "step", "params": {"time": 1234.5}},
    ]
    coef = [0.5, 0.4, 0.2, 0.3, 0.1, 0.05, 0.08, 0.6, -0.4, 0.25]
    if family == "composite":
        sensor += [
            {"kind": "omega_poly", "params": {"powers": [1, 2], "scale": 100.0}},
            {"kind": "omega_abs", "params": {"scale": 100.0}},
            {"kind": "omega_tpoly", "params": {"channel": 0, "powers": [1], "centre": 20.0,
                                               "t_scale": 40.0, "scale": 100.0}},
            {"kind": "drift_tpoly", "params": {"channel": 0, "powers": [0], "centre": 20.0,
                                               "scale": 40.0, "duration": 5400.0}},
        ]
        coef += [360000.0, 20.0, 5.0, 30.0, 0.2]
    for tm in sensor:
        tm.update(effect=tm["kind"], labels=[], applies="run" if tm["kind"] == "step"
                  else "sensor")
    return {"schema": LOOP_SCHEMA, "model": "composite" if family == "composite" else "bias-t",
            "input": {"unit": "deg/h", "scale_factor": None,
                      "temperatures": ["T_case", "T_fibre"],
                      "input_rate": family == "composite"},
            "calibration": {"family": family, "terms": sensor, "coefficients": coef,
                            "processing": {"target_blocks": 2500, "rate_window_s": 60.0},
                            "valid": {"temperature": [[0.0, 50.0], None],
                                      "temperature_rate_degC_per_min": [-0.1, 0.1]}}}


def _read(out, names):
    return {k: np.load(out / f"{k}.npy") for k in names}


@pytest.mark.parametrize("rows", [1000, 4099, 1 << 20])
@pytest.mark.parametrize("run_events", [False, True])
def test_streamed_bias_calibration_equals_the_in_memory_one(record, tmp_path, rows, run_events):
    d, rec = record
    doc = _doc("bias")
    ref = apply_calibration(doc, load(d / "rec.npz"), run_events=run_events)
    res = compensate_loop_stream(d / "rec.npz", doc, tmp_path / "out", rows=rows,
                                 run_events=run_events)
    got = _read(tmp_path / "out", ["time", "output", "outlier"])
    assert res.n == rec.n and res.columns == ("time", "output", "outlier")
    np.testing.assert_array_equal(got["time"], ref.columns["time"])
    np.testing.assert_array_equal(got["outlier"], ref.columns["outlier"])
    assert got["outlier"].sum() == 3 == res.outliers  # the three planted spikes
    np.testing.assert_allclose(got["output"], ref.columns["output"], rtol=0, atol=1e-9)
    assert res.skipped == ref.skipped and len(res.skipped) == (0 if run_events else 1)
    assert res.outside == ref.outside and {o["covariate"] for o in res.outside} == {
        "temperature 'T_case' (deg C)", "dT/dt (deg C/min)"}


@pytest.mark.parametrize("rows", [1000, 7777])
def test_streamed_composite_calibration_equals_the_in_memory_one(record, tmp_path, rows):
    d, rec = record
    doc = _doc("composite")
    ref = apply_calibration(doc, load(d / "rec.npz"))
    res = compensate_loop_stream(d / "rec.npz", doc, tmp_path / "out", rows=rows)
    got = _read(tmp_path / "out", ["rate", "outlier"])
    np.testing.assert_array_equal(got["outlier"], ref.columns["outlier"])
    ok = ~got["outlier"]
    assert ok.mean() > 0.99 and res.outliers == int((~ok).sum()) and res.rms_10s is None
    np.testing.assert_allclose(got["rate"][ok], ref.columns["rate"][ok], rtol=0, atol=1e-7)


def test_streamed_medians_are_numpys(tmp_path):
    rng = np.random.default_rng(3)
    x = np.concatenate([rng.standard_normal(5001), np.zeros(300), [-0.0, 7.5, -1e300, 1e-300]])
    rng.shuffle(x)
    for n in (x.size, x.size - 1, 1, 2):
        v = x[:n]
        med, passes = stream_median(lambda: iter(np.array_split(v, 7)), n)
        assert med == np.median(v) and 1 <= passes <= 4


def test_cli_streams_a_loop_document(record, tmp_path):
    d, rec = record
    (tmp_path / "loop.json").write_text(json.dumps(_doc("bias")))
    rc = cli.main(["-q", "compensate", str(d / "rec.npz"), "-p", str(tmp_path / "loop.json"),
                   "-o", str(tmp_path / "c.npz"), "--stream", "--chunk-rows", "2048",
                   "--json", str(tmp_path / "s.json")])
    assert rc == 0
    summ = json.loads((tmp_path / "s.json").read_text())
    assert summ["rows"] == rec.n and summ["outliers"] == 3
    assert [s["kind"] for s in summ["run_events_left_out"]] == ["step"]
    with np.load(tmp_path / "c.npz") as z:
        ref = apply_calibration(_doc("bias"), load(d / "rec.npz"))
        np.testing.assert_allclose(z["output"], ref.columns["output"], rtol=0, atol=1e-9)


@pytest.mark.parametrize("rows", [97, 1000, 1 << 20])
def test_streamed_10s_rms_equals_block_rms_across_gaps_and_flags(tmp_path, rows):
    """Reference: fogbayes.loop.metrics.block_rms (block_average, partial blocks kept,
    blocks restarting after each gap) on the whole arrays."""
    from fogbayes.loop.metrics import block_rms
    from fogbayes.stream import open_source, scan_time
    from fogbayes.stream.block_rms import StreamBlockRMS

    rng = np.random.default_rng(5)
    t = np.arange(6000) / 4.0
    t = np.delete(t, np.r_[1000:1100, 3001:3003, 4500:4510]) + 1.7e9  # gaps, Unix time
    t[2000:] += 0.013  # a stamp off the grid
    y = 0.3 + rng.standard_normal(t.size)
    flag = rng.random(t.size) < 0.05
    flag[2200:2260] = True  # a whole 10 s block flagged: no mean
    save(Recording(time=t, output=y), tmp_path / "r.npz")
    src = open_source(tmp_path / "r.npz")
    acc = StreamBlockRMS(scan_time(src, rows=rows), ("before", "after"))
    for a in range(0, t.size, rows):
        s = slice(a, a + rows)
        acc.add(a, t[s], {"before": y[s], "after": y[s] - 0.3}, ~flag[s])
    got = acc.rms()
    assert got["before"] == pytest.approx(block_rms(t, y, flag), rel=1e-12)
    assert got["after"] == pytest.approx(block_rms(t, y - 0.3, flag), rel=1e-12)
    after = y - 0.3
    ref = block_rms(t, after - after[~flag].mean(), flag)
    assert got["after_about_mean"] == pytest.approx(ref, rel=1e-9)


def test_cli_stream_summary_has_the_in_memory_before_after(record, tmp_path):
    from fogbayes.cli.compensate import loop_summary

    d, rec = record
    doc = _doc("bias")
    (tmp_path / "loop.json").write_text(json.dumps(doc))
    assert cli.main(["-q", "compensate", str(d / "rec.npz"), "-p", str(tmp_path / "loop.json"),
                     "-o", str(tmp_path / "c"), "--stream", "--chunk-rows", "3000",
                     "--json", str(tmp_path / "s.json")]) == 0
    got = json.loads((tmp_path / "s.json").read_text())["rms_10s_deg_h"]
    loaded = load(d / "rec.npz")
    ref = loop_summary(loaded, doc, apply_calibration(doc, loaded), rec_path="", params="",
                       out="")["rms_10s_deg_h"]
    for k in ("before", "after", "after_about_mean"):
        assert got[k] == pytest.approx(ref[k], rel=1e-9), k
