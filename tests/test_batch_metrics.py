"""Batched bias-stability reports equal the single-sensor `segment_report`, sensor by sensor."""

from __future__ import annotations

from types import SimpleNamespace as Seg

import numpy as np
import pytest

from fogbayes.batch.metrics import segment_reports
from fogbayes.stats.stability import segment_report


def _close(a, b, where="doc"):
    if isinstance(a, dict):
        assert list(a) == list(b), where  # same keys in the same order
        for k in a:
            _close(a[k], b[k], f"{where}.{k}")
    elif isinstance(a, list):
        assert len(a) == len(b), where
        for i, (x, y) in enumerate(zip(a, b)):
            _close(x, y, f"{where}[{i}]")
    elif isinstance(a, float):
        # block sums in another order: rounding only (values O(1), 10-600 terms)
        assert b == pytest.approx(a, rel=1e-12, abs=1e-13), where
    else:
        assert a == b, where


def test_batched_reports_equal_the_single_sensor_ones():
    rng = np.random.default_rng(4)
    n, S = 1800, 7
    t = np.arange(n) * 0.5 + 1.7e9  # Unix time stamps, 2 Hz
    t_gap = t.copy()
    t_gap[900:] += 40.0  # one sensor on its own clock, with a 40 s gap
    times = [t] * 5 + [t_gap, t + 0.25]
    before = rng.normal(0.3, 0.05, (S, n)) + np.linspace(0, 1, n) * rng.normal(1, 0.3, (S, 1))
    after = before - np.linspace(0, 1, n) * 0.9
    shared = [Seg(kind="soak", start=0, stop=600), Seg(kind="ramp_up", start=600, stop=1800)]
    segments = [shared] * 4 + [
        [Seg(kind="soak", start=0, stop=601), Seg(kind="ramp_up", start=601, stop=1800)],
        shared,
        [Seg(kind="soak", start=0, stop=1), Seg(kind="ramp_up", start=1, stop=1800)]]
    windows = (1.0, 10.0, 100.0, 500.0)  # 500 s leaves < 2 windows in the 300 s soak
    got = segment_reports(before, after, times, segments, windows=windows)
    for s in range(S):
        ref = segment_report(before[s], after[s], times[s], segments[s], windows=windows)
        _close(ref, got[s], f"sensor {s}")
    assert [r["window_s"] for r in got[0]["segments"][0]["stability"]] == [1.0, 10.0, 100.0]
    assert len(got[6]["segments"]) == 1  # a one-sample segment has no report, as before


def test_without_segments_only_the_full_record():
    rng = np.random.default_rng(0)
    t = np.arange(400.0)
    x = rng.normal(size=(3, 400))
    got = segment_reports(x, x * 0.5, [t] * 3)
    for s in range(3):
        _close(segment_report(x[s], x[s] * 0.5, t), got[s])
