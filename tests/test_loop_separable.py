"""The loop says which effects the record cannot separate (fogbayes/loop/separable.py):
sizes checked against least squares in closed form, a confounded candidate and a walk that
hides slow effects each named in a warning with a remedy that exists."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from fogbayes.data.recording import Recording
from fogbayes.loop.context import make_context
from fogbayes.loop.fitting import fit_terms
from fogbayes.effects.terms import Term, columns
from fogbayes.loop.bases import base_terms
from fogbayes.loop.separable import (POWER_Z, detectability, detectable_sizes,
                                     separability_warnings)
from fogbayes.loop.testbed import make_record


def test_sizes_are_least_squares_in_closed_form_under_white_noise():
    rec = make_record(None, seed=4, duration=2400.0, fs=1.0).recording
    ctx = make_context(rec, flicker=False)
    fit = fit_terms(ctx, base_terms(ctx, "bias-t", "2"))
    spec = fit.noise.spec
    assert spec.n_state == 1 and spec.random_walk
    theta = np.array([-60.0])  # a walk of e^-60 the white variance: white noise
    Z = np.column_stack([columns(Term("drift_exp", {"tau": tau}), ctx.bcov)
                         for tau in (200.0, 800.0, 2400.0)])
    a = 1e-3
    share, d = detectable_sizes(ctx, spec, theta, fit.noise.sigma2, fit.X, Z, a)
    ok = ctx.grid.mask > 0
    sw = 1.0 / np.sqrt(ctx.grid.w[ok])  # white-variance weights
    Xw, Zw = fit.X[ok] * sw[:, None], Z[ok] * sw[:, None]
    R = Zw - Xw @ np.linalg.lstsq(Xw, Zw, rcond=None)[0]
    want_share = 1.0 - np.sum(R * R, 0) / np.sum(Zw * Zw, 0)
    se = np.sqrt(fit.noise.sigma2 / np.sum(R * R, 0))
    want_d = (stats.norm.isf(a / 2) + POWER_Z) * se * np.max(np.abs(Z), 0)
    np.testing.assert_allclose(share, want_share, rtol=1e-8)
    np.testing.assert_allclose(d, want_d, rtol=1e-8)


def _with_offset_channel(rec):
    """The record with a second channel T_2 = 1.02 T_1: the gradient T_2 - T_1 is
    linear in T_1, which no programme separates from the temperature law."""
    T = np.asarray(rec.temperatures[:, 0], float)
    return Recording(time=rec.time, output=rec.output, temperatures=np.column_stack([T, 1.02 * T]),
                     temperature_names=("temperature", "temperature_2"), unit=rec.unit)


def test_a_candidate_the_base_fits_entirely_is_named_with_its_remedy():
    rec = _with_offset_channel(make_record(None, seed=5, duration=2400.0, fs=1.0).recording)
    ctx = make_context(rec)
    fit = fit_terms(ctx, base_terms(ctx, "bias-t", "2"))
    rows = {r["effect"]: r for r in detectability(ctx, fit, 0.01)}
    g = rows["temperature_gradient"]
    assert "temperature law" in g["confounded_with"]
    assert g["share_min_over_grid"] == pytest.approx(1.0, abs=1e-6)
    # a real driver of the generic programme is not confounded
    assert rows["temperature_rate"]["confounded_with"] is None
    warn = [w for w in separability_warnings(list(rows.values()), rms=0.1)
            if "temperature_gradient" in w]
    assert len(warn) == 1 and "any size" in warn[0] and "plan-chamber" in warn[0]


def test_a_random_walk_that_hides_slow_effects_is_said():
    noise = {"N": 0.05, "B": 0.05, "K": 3.0}  # a walk far above the white noise
    rec = make_record(None, seed=6, duration=3600.0, fs=1.0, noise=noise).recording
    ctx = make_context(rec)
    fit = fit_terms(ctx, base_terms(ctx, "bias-t", "2"))
    assert fit.noise.spec.random_walk
    rows = detectability(ctx, fit, 0.01)
    drift = next(r for r in rows if r["effect"] == "time_drift")
    assert drift["detectable_deg_h"] > 2.0 * drift["detectable_without_walk_deg_h"]
    warn = separability_warnings(rows, rms=0.5 * drift["detectable_deg_h"])
    assert any("random walk" in w and "warm-up or drift (time_drift)" in w
               and "--noise-prior" in w for w in warn)
