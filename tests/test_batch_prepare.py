"""A fleet's covariates, fit blocks and segments, computed per clock group, equal the
per-recording workflow's; 2-D temperature rates equal the 1-D ones row by row."""

from __future__ import annotations

import numpy as np
import pytest

from fogbayes.batch import prepare
from fogbayes.thermal.model import ThermalSpec
from fogbayes.preprocess.temperature_rate import temperature_rate
from fogbayes.simulate.scenarios import simulate
from fogbayes.thermal.data import fit_blocks, make_processing, sample_covariates
from fogbayes.thermal.workflow import thermal_segments

RTOL = 1e-12  # sums in another order: rounding only


@pytest.fixture(scope="module")
def fleet():
    recs = [simulate("thermal", seed=s, duration=1800.0, fs=2.0, sensor_id=f"s{s}").recording
            for s in range(4)]
    # a fifth on its own clock (shifted stamps): a group of one
    other = simulate("thermal", seed=9, duration=1800.0, fs=2.0).recording
    return recs + [other.replace(time=other.time + 0.25)]


@pytest.mark.parametrize("rate_method", ["savgol", "difference"])
def test_covariates_blocks_and_segments_equal_the_workflow(fleet, rate_method):
    spec = ThermalSpec(2, 1)
    proc = make_processing("default", rate_method=rate_method)
    zs = [z.T for z in prepare.covariates(fleet, spec, proc)]  # (c, n) each -> (n, c)
    rates = [r.rate("deg/h") for r in fleet]
    rng = np.random.default_rng(1)
    masks = [None, rng.random(fleet[1].n) < 0.05, None, np.zeros(fleet[3].n, bool), None]
    masks[3][10:40] = True  # whole 1 s blocks left out: they are dropped
    got = prepare.blocks(fleet, rates, zs, spec, proc, masks)
    segs = prepare.segments(fleet, [z[:, 0] for z in zs])
    for i, rec in enumerate(fleet):
        z_ref = sample_covariates(rec, spec, proc)
        # FFT vs direct filter: the two round differently. Measured difference 2.0e-11 on one
        # machine, < 1e-11 on another (~1e-12 relative to the tens of degC filtered); the
        # tolerance is 5x the largest measured and far below any physical rate (0.01 degC
        # noise over a 60 s window ~ 2e-4)
        np.testing.assert_allclose(zs[i], z_ref, rtol=1e-9, atol=1e-10)
        ref = fit_blocks(rec, rates[i], z_ref, spec, proc, masks[i])
        assert got[i].y.size == ref.y.size
        for a, b in zip(got[i], ref):
            # the block means inherit the covariates' FFT rounding (above)
            np.testing.assert_allclose(a, b, rtol=RTOL, atol=1e-9 if a is got[i].time else 1e-10)
        assert segs[i] == thermal_segments(rec, z_ref)
    assert got[3].y.size == got[0].y.size - 15  # samples 10-39 at 2 Hz: 15 blocks


@pytest.mark.parametrize("case", ["grid", "long_window", "irregular"])
def test_two_dimensional_rates_equal_rows(case):
    rng = np.random.default_rng(3)
    n = 3000
    t = np.arange(n) * 0.1
    if case == "irregular":
        t = t + rng.uniform(-0.02, 0.02, n)
    T = 20 + np.cumsum(rng.normal(0, 0.01, (3, n)), axis=1) + np.sin(t / 50.0)
    window = 60.0 if case == "long_window" else 3.0  # 601 samples: the FFT path
    got = temperature_rate(t, T, method="savgol", window_s=window)
    for row, g in zip(T, got):
        np.testing.assert_allclose(g, temperature_rate(t, row, method="savgol", window_s=window),
                                   rtol=1e-9, atol=1e-12)
