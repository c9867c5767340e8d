"""Bias and bias stability (paper 004 eqs. 12-13): direct NumPy, closed forms, paper numbers."""

from __future__ import annotations

import numpy as np
import pytest

from fogbayes.errors import TooShortError
from fogbayes.stats.stability import bias, bias_stability, improvement_pct, segment_report, stability_report


def test_equals_std_of_reshaped_window_means():
    rng = np.random.default_rng(0)
    fs, n = 200.0, 200 * 600  # the paper's 200 Hz, 10 min
    t = np.arange(n) / fs
    x = 0.3 * rng.normal(size=n) + np.sin(t / 60.0)
    for w in (1.0, 10.0, 100.0):
        m = int(w * fs)
        direct = x[: n // m * m].reshape(-1, m).mean(axis=1).std(ddof=1)
        assert bias_stability(x, t, w) == pytest.approx(direct, rel=1e-12)


def test_white_noise_closed_form():
    # white noise of std s averaged over m samples: Bs = s / sqrt(m). With 3600 windows
    # the estimate has relative sd 1/sqrt(2 * 3599) = 1.2 %; 5 % is > 4 sd
    rng = np.random.default_rng(1)
    fs, s = 10.0, 2.0
    t = np.arange(int(3600 * fs)) / fs
    assert bias_stability(s * rng.normal(size=t.size), t, 1.0) == pytest.approx(
        s / np.sqrt(fs), rel=0.05)


def test_paper_improvement_figure():
    # paper 004: full-temperature Bs 1.645749 -> 0.501541 deg/h is "69.53 % better"
    assert improvement_pct(1.645749, 0.501541) == pytest.approx(69.53, abs=0.005)
    assert bias(np.array([1.0, 2.0, 3.0])) == 2.0


def test_windows_never_straddle_gaps():
    # PAN-like bursts: 5 s at 50 Hz every 305 s; two levels, one per burst
    t = np.concatenate([np.arange(250) / 50.0 + k * 305.0 for k in range(4)])
    x = np.repeat([0.0, 1.0, 0.0, 1.0], 250)
    # 1 s windows: 5 per burst, 20 windows alternating in fives -> std of [0]*5+[1]*5...
    assert bias_stability(x, t, 1.0) == pytest.approx(np.std(np.repeat([0, 1, 0, 1], 5), ddof=1))
    rep = stability_report(x, x - 0.5, t)
    assert [r["window_s"] for r in rep["stability"]] == [1.0]  # no complete 10 s window
    with pytest.raises(TooShortError):
        bias_stability(x, t, 10.0)


def test_segment_report_per_segment():
    t = np.arange(0.0, 1000.0, 0.5)
    before = np.where(t < 500, 0.0, 2.0) + np.random.default_rng(2).normal(size=t.size) * 0.1
    after = before - np.where(t < 500, 0.0, 2.0)

    class Seg:  # any object with kind/start/stop works (e.g. preprocess.Segment)
        def __init__(self, kind, start, stop):
            self.kind, self.start, self.stop = kind, start, stop

    rep = segment_report(before, after, t, [Seg("soak", 0, 1000), Seg("soak", 1000, 2000)])
    full = rep["full"]["stability"][0]
    assert full["before"] > 0.9 and full["after"] < 0.1 and full["improvement_pct"] > 90
    for seg in rep["segments"]:  # inside each level nothing changes: ~0 % improvement
        assert abs(seg["stability"][0]["improvement_pct"]) < 1e-9
