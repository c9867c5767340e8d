"""Segmentation of thermal tests (soaks/ramps) and rate-table runs (plateaus), against the
truth of profiles built here with NumPy (independent of fogbayes.simulate)."""

from __future__ import annotations

import numpy as np
import pytest

from fogbayes.errors import FogbayesError, ShapeError, TooShortError
from fogbayes.preprocess import segment_rate_table, segment_thermal


def chamber_profile(pieces, fs=1.0, start=20.0):
    """Piecewise-linear temperature: pieces of (duration s, rate deg C/min)."""
    ts, Ts, edges, t0, T0 = [], [], [0.0], 0.0, start
    for d, r in pieces:
        t = t0 + np.arange(0.0, d, 1.0 / fs)
        ts.append(t)
        Ts.append(T0 + r / 60.0 * (t - t0))
        t0, T0 = t0 + d, T0 + r / 60.0 * d
        edges.append(t0)
    return np.concatenate(ts), np.concatenate(Ts), np.array(edges)


# Soak 20 deg C, ramp up at paper 004's 0.5 deg C/min to 40, soak, ramp down at 1 deg C/min.
PIECES = [(1200, 0.0), (2400, 0.5), (1800, 0.0), (1200, -1.0), (1200, 0.0)]
KINDS = ["soak", "ramp_up", "soak", "ramp_down", "soak"]


@pytest.mark.parametrize("seed", range(5))
def test_soak_ramp_profile(seed):
    t, T_true, edges = chamber_profile(PIECES)
    rng = np.random.default_rng(seed)
    # Thermometer noise 0.05 deg C and 0.1 deg C quantisation.
    T = np.round(T_true + rng.normal(0.0, 0.05, t.size), 1)
    segs = segment_thermal(t, T)
    assert [s.kind for s in segs] == KINDS
    # Segments tile the record.
    assert segs[0].start == 0 and segs[-1].stop == t.size
    assert all(a.stop == b.start for a, b in zip(segs, segs[1:]))
    # Boundaries within half the 60 s smoothing window of the true corners (measured
    # offsets 8-21 s: the smoothed rate crosses the threshold before the corner).
    for s, corner in zip(segs[1:], edges[1:-1]):
        assert abs(s.t_start - corner) <= 30.0
    for s, (d, rate) in zip(segs, PIECES):
        # Each segment's slope equals the truth's least-squares slope over the same samples;
        # the noise part is 0.06 / sqrt(sum (t - tbar)^2) < 2e-6 deg C/s for >= 1100 s.
        idx = slice(s.start, s.stop)
        tc = t[idx] - t[idx].mean()
        truth = np.dot(tc, T_true[idx]) / np.dot(tc, tc)
        assert s.mean_rate == pytest.approx(truth, abs=1e-5)
        # and is near the nominal ramp (the ends hold a few seconds of the soaks): 2 %.
        assert s.mean_rate * 60 == pytest.approx(rate, abs=0.02 * max(abs(rate), 0.5))
    # Soak means: soak samples never include ramp samples, so only noise remains
    # (0.06 / sqrt(1100) = 0.002 deg C).
    for s, level in zip(segs[::2], [20.0, 40.0, 20.0]):
        assert s.mean_temperature == pytest.approx(level, abs=0.01)


def test_short_disturbance_is_merged():
    t, T, _ = chamber_profile([(1800, 0.0), (1200, 1.0), (1800, 0.0)])
    T = T.copy()
    bump = (t > 600) & (t < 700)  # a 100 s, +-0.5 deg C wobble in the first soak
    T[bump] += 0.5 * np.sin(2 * np.pi * (t[bump] - 600) / 100)
    segs = segment_thermal(t, T, min_duration=300.0)
    assert [s.kind for s in segs] == ["soak", "ramp_up", "soak"]
    # With a shorter min_duration the wobble becomes its own ramps.
    assert len(segment_thermal(t, T, min_duration=20.0)) > 3


def rate_table_run(fs=2.0, seed=0):
    """Soak at rest at each temperature, then 60 s at each rate; 2 deg C/min between."""
    temps, rates = [-20.0, 20.0, 60.0], [5.0, -10.0, 50.0, 0.0]
    t_parts, w_parts, T_parts, truth = [], [], [], []
    t0 = 0.0

    def add(d, w, T_of):
        nonlocal t0
        s = np.arange(0.0, d, 1.0 / fs)
        t_parts.append(t0 + s)
        w_parts.append(np.full(s.size, w))
        T_parts.append(T_of(s))
        t0 += d

    for i, level in enumerate(temps):
        if i:
            prev = temps[i - 1]
            add((level - prev) * 30.0, 0.0, lambda s, p=prev: p + s / 30.0)
        truth.append((t0, t0 + 300.0, level, 0.0))
        add(300.0, 0.0, lambda s, v=level: np.full(s.size, v))
        for w in rates:
            truth.append((t0, t0 + 60.0, level, w))
            add(60.0, w, lambda s, v=level: np.full(s.size, v))
    rng = np.random.default_rng(seed)
    t = np.concatenate(t_parts)
    W = np.concatenate(w_parts) + rng.normal(0.0, 1e-3, t.size)
    T = np.concatenate(T_parts) + rng.normal(0.0, 0.05, t.size)
    return t, W, T, truth, temps, rates


def test_rate_table_plateaus():
    t, W, T, truth, temps, rates = rate_table_run()
    rt = segment_rate_table(t, W, T, min_duration=30.0)
    assert np.allclose(rt.temperature_levels, temps, atol=0.02)  # noise 0.05/sqrt(>500)
    assert np.allclose(rt.rate_levels, sorted(rates), atol=1e-3)  # levels ascend
    grid = rt.grid()
    assert grid.shape == (3, 4) and (grid >= 0).all()  # the full 3 x 4 grid
    for c in rt.cells:
        # Each cell lies inside one true interval of constant (T, Omega) ...
        inside = [(a, b, Tl, w) for a, b, Tl, w in truth if a <= c.t_start and c.t_stop < b]
        assert len(inside) == 1, c
        _, _, Tl, w = inside[0]
        # ... with the right labels.
        assert rt.temperature_levels[c.i] == pytest.approx(Tl, abs=0.02)
        assert rt.rate_levels[c.j] == pytest.approx(w, abs=1e-3)
    # Every 60 s rate plateau is found and covered to >= 90 % (the rate-steadiness window
    # eats 2 samples at each step: 116 of 120 samples), except the last one before a
    # temperature ramp: the 60 s temperature-rate smoother sees the ramp up to 30 s early
    # (measured: 76 of 120 samples kept), so there we ask for half.
    ramp_starts = [b for a, b, Tl, w in truth if w == 0.0 and b - a == 60.0][:-1]
    for a, b, Tl, w in truth:
        if b - a != 60.0:
            continue
        n_true = np.count_nonzero((t >= a) & (t < b))
        best = max(np.count_nonzero((t[c.start:c.stop] >= a) & (t[c.start:c.stop] < b))
                   for c in rt.cells)
        assert best >= (0.5 if b in ramp_starts else 0.9) * n_true, (a, Tl, w)


@pytest.mark.parametrize("n", [1, 2, 6, 100, 1001])
def test_moving_range_equals_scipy_filters(n):
    """The plateau detector's window range (strided for short windows) is SciPy's
    maximum_filter1d - minimum_filter1d with mode="nearest", exactly."""
    from scipy.ndimage import maximum_filter1d, minimum_filter1d

    from fogbayes.preprocess.rate_table import _moving_range

    x = np.random.default_rng(n).normal(size=n).round(1)  # rounding makes ties
    for w in (3, 5, 7, 31, 33, 101):
        ref = maximum_filter1d(x, w, mode="nearest") - minimum_filter1d(x, w, mode="nearest")
        np.testing.assert_array_equal(_moving_range(x, w), ref)


def test_rate_table_schedule_hand_computed():
    t = np.arange(10.0)
    sched = [(0.0, 5.0, 20.0, 1.0), (5.0, 10.0, 20.0, 2.0)]
    rt = segment_rate_table(t, schedule=sched, trim_s=1.0)
    # t >= t_start + 1 and t < t_stop: samples 1..4 and 6..9.
    assert [(c.start, c.stop) for c in rt.cells] == [(1, 5), (6, 10)]
    assert [(c.i, c.j) for c in rt.cells] == [(0, 0), (0, 1)]
    assert rt.rate_levels.tolist() == [1.0, 2.0] and rt.temperature_levels.tolist() == [20.0]
    # The same run as the detected one, from its own schedule.
    tt, W, T, truth, temps, rates = rate_table_run()
    plan = [(a, b, Tl, w) for a, b, Tl, w in truth if b - a == 60.0]
    rs = segment_rate_table(tt, schedule=plan)
    assert (rs.grid() >= 0).all() and len(rs.cells) == 12
    assert all(np.all((tt[c.start:c.stop] >= p[0]) & (tt[c.start:c.stop] < p[1]))
               for c, p in zip(rs.cells, plan))


def test_segment_errors():
    t = np.arange(100.0)
    with pytest.raises(ShapeError, match="temperature has 99"):
        segment_thermal(t, np.zeros(99))
    with pytest.raises(TooShortError, match="smooth_s=500 s is longer than the record"):
        segment_thermal(t, np.zeros(100), smooth_s=500.0)
    with pytest.raises(FogbayesError, match="rate_threshold"):
        segment_thermal(t, np.zeros(100), rate_threshold=-1.0, smooth_s=10.0)
    with pytest.raises(ShapeError, match="entry 1 has 3"):
        segment_rate_table(t, schedule=[(0, 10, 20, 1), (10, 20, 20)])
    with pytest.raises(TooShortError, match="holds no sample"):
        segment_rate_table(t, schedule=[(500.0, 600.0, 20.0, 1.0)])
    with pytest.raises(FogbayesError, match="ends before it starts"):
        segment_rate_table(t, schedule=[(10.0, 5.0, 20.0, 1.0)])
    with pytest.raises(FogbayesError, match="reference input rate"):
        segment_rate_table(t, None, np.zeros(100))
    with pytest.raises(TooShortError, match="no plateau"):
        segment_rate_table(t, np.sin(t), min_duration=50.0)


def _merge_reference(labels, t, min_duration):
    """The merge rule written plainly (the Python implementation the compiled loop replaced)."""
    edges = np.flatnonzero(np.diff(labels)) + 1
    runs = [[int(labels[a]), int(a), int(b)]
            for a, b in zip(np.r_[0, edges], np.r_[edges, labels.size])]
    end = np.r_[t[1:], t[-1] + np.median(np.diff(t))]
    while len(runs) > 1:
        d = [float(end[r[2] - 1] - t[r[1]]) for r in runs]
        i = int(np.argmin(d))
        if d[i] >= min_duration:
            break
        left = runs[i - 1] if i > 0 else None
        right = runs[i + 1] if i + 1 < len(runs) else None
        if left is not None and right is not None and left[0] == right[0]:
            runs[i][0] = left[0]
        elif left is None or (right is not None and d[i + 1] > d[i - 1]):
            runs[i][0] = right[0]
        else:
            runs[i][0] = left[0]
        merged = [runs[0]]
        for r in runs[1:]:
            if r[0] == merged[-1][0]:
                merged[-1] = [r[0], merged[-1][1], r[2]]
            else:
                merged.append(r)
        runs = merged
    return runs


@pytest.mark.parametrize("backend", ["segment_loops", "segment_rules"])
@pytest.mark.parametrize("seed", range(6))
def test_compiled_merge_equals_the_plain_rule(seed, backend):
    """Both backends of the one definition (:mod:`fogbayes.preprocess.segment_rules` run as
    Python, and compiled by Numba) against the reference above; and against each other
    exactly (integer labels, and the same float operations in the same order)."""
    import importlib

    loops = importlib.import_module(f"fogbayes.preprocess.{backend}")
    merge_runs, run_stats = loops.merge_runs, loops.run_stats

    rng = np.random.default_rng(seed)
    n = 400
    t = np.cumsum(rng.uniform(0.5, 1.5, n))  # irregular steps: durations differ, ties rare
    if seed % 2:
        t = np.arange(n, dtype=float)  # a grid: many equal durations (the tie rules)
    # flickering labels: runs of 1-40 samples of -1/0/1
    labels = np.repeat(rng.integers(-1, 2, n), rng.integers(1, 40, n))[:n].reshape(1, n)
    labels = np.vstack([labels, rng.integers(-1, 2, (2, n))])  # and pure noise rows
    end = np.r_[t[1:], t[-1] + np.median(np.diff(t))]
    # labels -1/0/1 as rates against a threshold of 0.5
    lab, start, stop, count = merge_runs(labels.astype(float), 0.5, t, end, 30.0)
    T = rng.normal(20.0, 1.0, labels.shape)
    mean, slope = run_stats(T, t, start, stop, count)
    for s in range(labels.shape[0]):
        ref = _merge_reference(labels[s], t, 30.0)
        got = [[int(lab[s, k]), int(start[s, k]), int(stop[s, k])] for k in range(count[s])]
        assert got == ref
        for k, (_, a, b) in enumerate(ref):
            assert mean[s, k] == pytest.approx(T[s, a:b].mean(), rel=1e-13)
            tc = t[a:b] - t[a:b].mean()
            want = 0.0 if b - a < 2 else np.dot(tc, T[s, a:b] - T[s, a:b].mean()) / np.dot(tc, tc)
            assert slope[s, k] == pytest.approx(want, rel=1e-9, abs=1e-13)
    if backend == "segment_rules":
        from fogbayes.preprocess import segment_loops as compiled

        other = compiled.merge_runs(labels.astype(float), 0.5, t, end, 30.0)
        assert all(np.array_equal(a, b) for a, b in zip((lab, start, stop, count), other))
        np.testing.assert_array_equal(np.stack([mean, slope]), np.stack(
            compiled.run_stats(T, t, *other[1:])))
