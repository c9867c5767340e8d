"""Model-free scans of the residual (fogbayes.loop.scans): find planted structure only."""

from __future__ import annotations

import numpy as np
import pytest

from fogbayes.data import Metadata, Recording
from fogbayes.loop.context import make_context
from fogbayes.loop.fitting import fit_terms
from fogbayes.loop.scans import scan_unexplained
from fogbayes.effects.terms import Term
from fogbayes.loop.bases import base_terms
from fogbayes.loop.testbed import make_record


def _kinds(found):
    return {(u["kind"], u["detail"].get("covariate")) for u in found}


@pytest.fixture(scope="module")
def cubic():
    """A 2 h thermal test with a strong quartic bias the cubic base model lacks."""
    rec = make_record("temperature_order", seed=4, duration=7200.0, fs=1.0, magnitude=8.0).recording
    return make_context(rec, target_blocks=800)


def test_covariate_scan_finds_the_missing_temperature_structure(cubic):
    fit = fit_terms(cubic, base_terms(cubic, "bias-t"))
    found = scan_unexplained(cubic, fit, seed=0)
    assert ("covariate", "temperature") in _kinds(found)


def test_nothing_unexplained_once_the_effect_is_in_the_model(cubic):
    terms = base_terms(cubic, "bias-t")
    tp = terms[1]
    full = terms[:1] + [Term("tpoly", {**tp.params, "powers": [1, 2, 3, 4]})]
    found = scan_unexplained(cubic, fit_terms(cubic, full), seed=0)
    # The temperature structure is gone once the quartic is in. Other
    # covariates may still be flagged at alpha / 6 each (this seed reports dT/dt at
    # p = 0.001 after the noise refit, 0.01 at the fixed noise model: the refitted ratio is
    # somewhat anti-conservative, see fogbayes.loop.scans).
    assert ("covariate", "temperature") not in _kinds(found)


def test_a_fast_line_above_the_block_nyquist_is_reported():
    fs, n = 10.0, 36000
    t = np.arange(n) / fs
    rng = np.random.default_rng(5)
    x = rng.standard_normal(n) + 0.3 * np.sin(2 * np.pi * 2.0 * t)  # 2 Hz, SNR per bin ~ 800
    rec = Recording(time=t, output=x, meta=Metadata(sample_rate=fs))
    ctx = make_context(rec, target_blocks=800)
    fit = fit_terms(ctx, [Term("intercept", {})])
    lines = [u for u in scan_unexplained(ctx, fit, seed=0) if u["kind"] == "spectral_line"]
    assert lines and lines[0]["detail"]["frequency_hz"] == pytest.approx(2.0, abs=2e-3)
    clean = Recording(time=t, output=rng.standard_normal(n), meta=Metadata(sample_rate=fs))
    cctx = make_context(clean, target_blocks=800)
    assert not scan_unexplained(cctx, fit_terms(cctx, [Term("intercept", {})]), seed=0)


def test_a_noise_model_at_its_bound_is_reported_as_unexplained():
    """Paper 000's rate table under the default composite orders (linear scale, quadratic
    bias) leaves the scale's T x W^k products and the operating-time drift in the residual:
    the random walk goes to the top of its range. The paper's own orders leave it free."""
    from fogbayes.loop.scans import noise_bound_scan
    from fogbayes.simulate import simulate

    ctx = make_context(simulate("paper000", seed=0, dwell=20.0).recording)
    short = noise_bound_scan(fit_terms(ctx, base_terms(ctx, "composite")))
    assert [u["detail"]["component"] for u in short] == ["random_walk"]
    assert short[0]["kind"] == "noise_model_at_bound"
    assert noise_bound_scan(fit_terms(ctx, base_terms(ctx, "composite", "2,3,2,2"))) == []
