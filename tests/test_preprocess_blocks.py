"""Block averaging and paper 004's 1 s / 10 s smoothing, against hand-computed values."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fogbayes import Metadata, Recording
from fogbayes.errors import FogbayesError, ShapeError, TimeOrderError, TooShortError
from fogbayes.preprocess import block_average, block_index, paper004_smoothing

# Means of at most a few hundred exact small numbers: float64 rounding is ~1e-13.
TOL = 1e-12


def test_hand_computed_blocks_and_partial_last_block():
    t = np.arange(10.0)  # 1 Hz; the run covers [0, 10)
    x = np.arange(1.0, 11.0)
    b = block_average(x, 3.0, time=t)  # blocks [0,3) [3,6) [6,9); [9,12) is incomplete
    assert b.time.tolist() == [1.0, 4.0, 7.0]
    assert b.mean.tolist() == [2.0, 5.0, 8.0]
    assert b.count.tolist() == [3, 3, 3]
    assert b.start.tolist() == [0, 3, 6] and b.stop.tolist() == [3, 6, 9]
    k = block_average(x, 3.0, time=t, partial="keep")
    assert k.time.tolist() == [1.0, 4.0, 7.0, 9.0]
    assert k.mean.tolist() == [2.0, 5.0, 8.0, 10.0]
    assert k.count.tolist() == [3, 3, 3, 1]
    # A window that divides the run exactly leaves no partial block.
    assert block_average(x, 5.0, time=t).mean.tolist() == [3.0, 8.0]
    # window = one sample interval: the identity.
    one = block_average(x, 1.0, time=t)
    assert one.mean.tolist() == x.tolist() and one.time.tolist() == t.tolist()


@pytest.mark.parametrize("t0", [0.0, 1.7e9])  # also a Unix-time origin
def test_200hz_to_1s_time_stamps(t0):
    n = 1000
    t = t0 + np.arange(n) / 200.0  # time stamps with float rounding on block edges
    b = block_average(np.arange(n, dtype=float), 1.0, time=t)
    assert b.count.tolist() == [200] * 5  # no sample slips into the neighbouring block
    # Block b holds samples 200 b ... 200 b + 199: mean index 200 b + 99.5, mean time
    # t0 + b + 0.4975.
    assert np.allclose(b.mean, 200 * np.arange(5) + 99.5, rtol=0, atol=TOL)
    # At t0 = 1.7e9 a time stamp carries ~2.4e-7 s of rounding; the mean keeps it there.
    assert np.allclose(b.time - t0, np.arange(5) + 0.4975, rtol=0, atol=1e-6 if t0 else TOL)


def test_blocks_are_cut_at_gaps():
    t = np.r_[np.arange(10.0), 25.0 + np.arange(10.0)]  # gap of 16 s after t = 9
    x = t.copy()
    b = block_average(x, 4.0, time=t)
    # Run 1: [0..3] [4..7], partial [8, 9] dropped; run 2 restarts at 25: [25..28]
    # [29..32], partial [33, 34] dropped. No block mixes the two runs.
    assert b.mean.tolist() == [1.5, 5.5, 26.5, 30.5]
    assert b.start.tolist() == [0, 4, 10, 14] and b.stop.tolist() == [4, 8, 14, 18]
    k = block_average(x, 4.0, time=t, partial="keep")
    assert k.mean.tolist() == [1.5, 5.5, 8.5, 26.5, 30.5, 33.5]
    assert k.count.tolist() == [4, 4, 2, 4, 4, 2]
    bi = block_index(t, 4.0, partial="keep")
    assert bi.complete.tolist() == [True, True, False, True, True, False]
    assert bi.segment.tolist() == [0, 0, 0, 1, 1, 1]


def test_mask_leaves_flagged_samples_out():
    t = np.arange(8.0)
    x = np.array([1.0, 2.0, 1000.0, 3.0, 5.0, 7.0, 9.0, 11.0])
    mask = np.zeros(8, bool)
    mask[2] = True
    b = block_average(x, 4.0, time=t, mask=mask)
    assert b.mean.tolist() == [2.0, 8.0]  # (1 + 2 + 3) / 3, (5 + 7 + 9 + 11) / 4
    assert b.time.tolist() == [(0 + 1 + 3) / 3, 5.5]  # stamp of the samples averaged
    assert b.count.tolist() == [3, 4]
    mask[:4] = True  # a block with nothing left: NaN and count 0 (arrays) ...
    b = block_average(x, 4.0, time=t, mask=mask)
    assert np.isnan(b.mean[0]) and b.count[0] == 0 and b.time[0] == 1.5
    rec = Recording(time=t, output=x)
    r = block_average(rec, 4.0, mask=mask)  # ... and left out of a Recording
    assert r.recording.output.tolist() == [8.0] and r.count.tolist() == [4]


def test_recording_all_columns():
    t = np.arange(12) * 0.5  # 2 Hz
    temps = np.c_[20.0 + t, 30.0 - 2.0 * t]
    rec = Recording(time=t, output=3.0 * t, unit="deg/s", temperatures=temps,
                    temperature_names=("inner", "outer"), input_rate=np.repeat([1.0, 5.0], 6),
                    meta=Metadata(sensor_id="fog-1", sample_rate=2.0))
    r = block_average(rec, 3.0)  # 6 samples per block, 2 blocks
    out = r.recording
    assert out.unit == "deg/s" and out.temperature_names == ("inner", "outer")
    assert out.time.tolist() == [1.25, 4.25]
    assert np.allclose(out.output, [3.75, 12.75], rtol=0, atol=TOL)
    assert np.allclose(out.temperatures, [[21.25, 27.5], [24.25, 21.5]], rtol=0, atol=TOL)
    assert out.input_rate.tolist() == [1.0, 5.0]
    assert out.meta.sample_rate == pytest.approx(1 / 3.0) and out.meta.sensor_id == "fog-1"
    assert r.count.tolist() == [6, 6]


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), window=st.floats(0.3, 6.0))
def test_blocks_partition_irregular_gapped_time(seed, window):
    rng = np.random.default_rng(seed)
    dt = rng.uniform(0.05, 0.15, 400)  # jittered around 0.1 s
    dt[rng.choice(399, 3, replace=False)] += rng.uniform(1.0, 5.0, 3)  # three gaps
    t = np.cumsum(dt)
    x = rng.normal(size=t.size)
    b = block_average(x, window, time=t, partial="keep")
    # Every sample is in exactly one block, so the count-weighted means add up.
    assert b.count.sum() == t.size
    assert np.isclose(np.sum(b.count * b.mean), x.sum(), rtol=0, atol=1e-9)
    # No block spans more than its window or straddles a gap.
    big = np.diff(t) > 1.5 * np.median(np.diff(t))
    for a, z in zip(b.start, b.stop):
        assert t[z - 1] - t[a] < window
        assert not big[a:z - 1].any()


def test_paper004_smoothing_hand_computed():
    t = np.arange(1200) * 0.05  # 20 Hz, 60 s
    temps = np.c_[20.0 + 0.01 * t, 30.0 - 0.02 * t]
    out = t.copy()
    mask = np.zeros(t.size, bool)
    out[45] = 1e6  # a spike in row 2, flagged
    mask[45] = True
    rec = Recording(time=t, output=out, temperatures=temps)
    s = paper004_smoothing(rec, mask=mask)
    r = s.recording
    b = np.arange(60)
    # 1 s rows: samples 20 b ... 20 b + 19, mean time b + 0.475 (row 2 without t = 2.25).
    row2 = (np.sum(2.0 + 0.05 * np.arange(20)) - 2.25) / 19
    want = b + 0.475
    want[2] = row2
    assert np.allclose(r.time, want, rtol=0, atol=TOL) and np.allclose(r.output, want, atol=TOL)
    assert s.count[2] == 19 and s.count[0] == 20 and r.meta.sample_rate == 1.0
    # Temperatures: 10 s means (all samples, mask ignored) held over their ten 1 s rows:
    # block g has mean time 10 g + 4.975.
    g_time = 10 * (b // 10) + 4.975
    assert np.allclose(r.temperatures[:, 0], 20.0 + 0.01 * g_time, rtol=0, atol=TOL)
    assert np.allclose(r.temperatures[:, 1], 30.0 - 0.02 * g_time, rtol=0, atol=TOL)
    # Rate = difference of consecutive 10 s means / 10 s: exact on these ramps.
    assert np.allclose(s.temperature_rate, [[0.01, -0.02]], rtol=0, atol=1e-13)
    # align="interp": 20 + 0.01 t at the 1 s stamps between the first and last 10 s
    # block times (4.975 ... 54.975), the end block means beyond them.
    i = paper004_smoothing(rec, align="interp").recording
    tm = i.time
    inner = (tm >= 4.975) & (tm <= 54.975)
    assert np.allclose(i.temperatures[inner, 0], 20.0 + 0.01 * tm[inner], rtol=0, atol=TOL)
    assert np.allclose(i.temperatures[tm < 4.975, 0], 20.0 + 0.01 * 4.975, rtol=0, atol=TOL)


def test_paper004_smoothing_restarts_after_gap():
    t = np.r_[np.arange(600) * 0.05, 100.0 + np.arange(400) * 0.05]  # 30 s, gap, 20 s
    rec = Recording(time=t, output=np.zeros(t.size), temperatures=20.0 + 0.01 * t)
    s = paper004_smoothing(rec)
    assert s.recording.n == 50  # 30 + 20 whole seconds
    # Row 30 is the first second after the gap; its 10 s block is [100, 110).
    assert s.recording.time[30] == pytest.approx(100.475, abs=TOL)
    assert s.recording.temperatures[30, 0] == pytest.approx(20.0 + 0.01 * 104.975, abs=TOL)
    assert np.allclose(s.temperature_rate, 0.01, rtol=0, atol=1e-13)


def test_bad_windows_and_shapes():
    t = np.arange(100) * 0.1
    x = np.zeros(100)
    with pytest.raises(TooShortError, match="shorter than the sample interval"):
        block_average(x, 0.05, time=t)
    with pytest.raises(TooShortError, match="longer than the record"):
        block_average(x, 20.0, time=t)
    with pytest.raises(ShapeError, match="values have shape"):
        block_average(x[:99], 1.0, time=t)
    with pytest.raises(ShapeError, match="mask has shape"):
        block_average(x, 1.0, time=t, mask=np.zeros(10, bool))
    with pytest.raises(ShapeError, match="time stamps"):
        block_average(x, 1.0)
    with pytest.raises(TimeOrderError):
        block_average(x, 1.0, time=t[::-1])
    with pytest.raises(FogbayesError, match="positive"):
        block_average(x, -1.0, time=t)
    with pytest.raises(FogbayesError, match="partial"):
        block_average(x, 1.0, time=t, partial="pad")
    rec = Recording(time=t, output=x, temperatures=x + 20)
    with pytest.raises(FogbayesError, match="whole multiple"):
        paper004_smoothing(rec, rate_window_s=1.0, temperature_window_s=2.5)
    with pytest.raises(TooShortError, match="temperature_window_s"):
        paper004_smoothing(rec, temperature_window_s=20.0)
