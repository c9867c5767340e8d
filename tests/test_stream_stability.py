"""The bias stability before/after of a streamed compensation equals the in-memory report.

Reference: :func:`fogbayes.stats.stability.stability_report` on the whole arrays (paper
004 eqs. 12-13 on complete blocks cut at gaps; its own figures are checked against the
paper in tests/test_metrics.py). Tolerance: 1e-10 relative; the streamed sums differ
only in the order of additions (a block cut by a chunk edge is summed in two parts) and
in taking m_b about the first block's mean instead of the overall mean.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

import fogbayes.cli as cli
from fogbayes.data import Recording, load, save
from fogbayes.stats.stability import stability_report
from fogbayes.stream import open_source, scan_time
from fogbayes.stream.stability import StreamStability


def _assert_same(got: dict, ref: dict) -> None:
    assert got["bias_before"] == pytest.approx(ref["bias_before"], rel=1e-12)
    assert got["bias_after"] == pytest.approx(ref["bias_after"], rel=1e-10, abs=1e-12)
    assert got["duration_s"] == ref["duration_s"]
    assert [r["window_s"] for r in got["stability"]] == [r["window_s"] for r in ref["stability"]]
    for g, r in zip(got["stability"], ref["stability"]):
        for k in ("before", "after", "improvement_pct"):
            assert g[k] == pytest.approx(r[k], rel=1e-10), (g["window_s"], k)


@pytest.mark.parametrize("rows", [97, 1000, 1 << 20])
def test_streamed_stability_equals_the_report_across_gaps(tmp_path, rows):
    rng = np.random.default_rng(11)
    t = np.arange(40_000) / 4.0
    t = np.delete(t, np.r_[1000:1100, 3001:3003, 20_500:20_710]) + 1.7e9  # gaps, Unix time
    t[2000:] += 0.013  # a stamp off the grid
    # a large bias under a small stability: the shifted sums must keep the digits
    before = 1e3 + 0.02 * rng.standard_normal(t.size) + 1e-4 * (t - t[0])
    after = before - 1e3 - 1e-4 * (t - t[0])
    save(Recording(time=t, output=before), tmp_path / "r.npz")
    acc = StreamStability(scan_time(open_source(tmp_path / "r.npz"), rows=rows))
    for a in range(0, t.size, rows):
        s = slice(a, a + rows)
        acc.add(a, t[s], before[s], after[s])
    got = acc.report()
    ref = stability_report(before, after, t)
    assert [r["window_s"] for r in ref["stability"]] == [1.0, 10.0, 100.0]
    _assert_same(got, ref)


def test_windows_the_record_cannot_fill_have_no_row(tmp_path):
    t = np.arange(0, 150.0, 2.0)  # 0.5 Hz, 150 s: 1 s is below a step, 100 s fits once
    y = np.random.default_rng(2).standard_normal(t.size)
    save(Recording(time=t, output=y), tmp_path / "r.npz")
    acc = StreamStability(scan_time(open_source(tmp_path / "r.npz"), rows=1024))
    acc.add(0, t, y, 0.5 * y)
    got, ref = acc.report(), stability_report(y, 0.5 * y, t)
    assert [r["window_s"] for r in got["stability"]] == [10.0]
    _assert_same(got, ref)


@pytest.fixture(scope="module")
def thermal_run(tmp_path_factory):
    from fogbayes.simulate import simulate

    d = tmp_path_factory.mktemp("stream_stability")
    rec = simulate("thermal", duration=3600.0, fs=2.0, seed=4).recording
    save(rec, d / "rec.npz")
    save(rec, d / "rec.csv")
    assert cli.main(["-q", "fit", str(d / "rec.csv"), "-m", "bias-t", "--json",
                     str(d / "fit.json")]) == 0
    return d


def test_cli_stream_summary_has_the_in_memory_stability(thermal_run, tmp_path):
    d = thermal_run
    assert cli.main(["-q", "compensate", str(d / "rec.npz"), "-p", str(d / "fit.json"),
                     "-o", str(tmp_path / "c"), "--stream", "--chunk-rows", "3000",
                     "--json", str(tmp_path / "s.json")]) == 0
    assert cli.main(["-q", "compensate", str(d / "rec.csv"), "-p", str(d / "fit.json"),
                     "-o", str(tmp_path / "c.csv"), "--json", str(tmp_path / "m.json")]) == 0
    got = json.loads((tmp_path / "s.json").read_text())
    ref = json.loads((tmp_path / "m.json").read_text())
    assert got["unit"] == ref["unit"]
    _assert_same(got["metrics"], ref["metrics"])
    assert got["metrics"]["stability"][0]["after"] < got["metrics"]["stability"][0]["before"]


def test_streamed_loop_summary_has_the_in_memory_stability(tmp_path):
    from test_stream_loop import _doc  # the loop document with every bias-family term

    from fogbayes.cli.compensate import loop_summary
    from fogbayes.loop.calibration import apply_calibration
    from fogbayes.stream.loop_calibration import compensate_loop_stream

    rng = np.random.default_rng(7)
    t = 1000.0 + np.arange(7200) / 2.0
    T1 = 20 + 20 * np.sin(2 * np.pi * (t - t[0]) / 3600.0)
    rec = Recording(time=t, output=0.5 + 0.01 * (T1 - 20) + 0.05 * rng.standard_normal(t.size),
                    unit="deg/h", temperatures=np.column_stack([T1, T1 + 0.3]),
                    temperature_names=("T_case", "T_fibre"))
    save(rec, tmp_path / "rec.npz")
    doc = _doc("bias")
    res = compensate_loop_stream(tmp_path / "rec.npz", doc, tmp_path / "out", rows=1500)
    loaded = load(tmp_path / "rec.npz")
    ref = loop_summary(loaded, doc, apply_calibration(doc, loaded), rec_path="", params="",
                       out="")["metrics"]
    _assert_same(res.metrics, ref)
