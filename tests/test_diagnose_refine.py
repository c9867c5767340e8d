"""Placing an accepted step inside its block (fogbayes.diagnose.refine.polish_step).

A large step (16x the registry's 0.2 deg/h) planted a third of the way into a block: at
the block-boundary time the screening can offer, that block is left a third stepped
(about 1 deg/h off, ten times the white noise of a block mean), so the polished time must
be within 1/20 of a block of the truth and the refitted likelihood must rise. With the
time already on the true boundary it must change nothing.
"""

from __future__ import annotations

import numpy as np

from fogbayes.diagnose.context import make_context
from fogbayes.diagnose.fitting import fit_terms
from fogbayes.diagnose.refine import STEP_SUBDIVISIONS, polish_step
from fogbayes.diagnose.terms import Term
from fogbayes.loop.bases import base_terms
from fogbayes.loop.testbed import make_record


def _fits(offset_blocks: float):
    rec0 = make_record(None, seed=3, duration=3600.0, fs=10.0, noise="white").recording
    ctx0 = make_context(rec0, target_blocks=500)
    edge = float(ctx0.grid.t[250] - 0.5 * ctx0.grid.dt)   # a block boundary mid-record
    true_time = edge + offset_blocks * ctx0.grid.dt
    rec = make_record("step", seed=3, duration=3600.0, fs=10.0, noise="white", magnitude=16.0,
                      effect_params={"time": true_time}).recording
    ctx = make_context(rec, target_blocks=500)
    base = fit_terms(ctx, base_terms(ctx, "bias-t"))
    step = Term("step", {"effect": "step", "time": edge})
    alt = fit_terms(ctx, base.terms + (step,), spec=base.noise.spec, theta0=base.noise.theta)
    return ctx, base, alt, true_time, edge


def test_a_step_inside_a_block_is_placed_within_a_twentieth_of_a_block():
    ctx, base, alt, true_time, edge = _fits(1.0 / 3.0)
    out = polish_step(ctx, base, alt)
    got = out.terms[-1].params["time"]
    assert got != edge
    assert abs(got - true_time) <= ctx.grid.dt / STEP_SUBDIVISIONS
    assert out.loglik > alt.loglik + 10.0
    rms = lambda f: np.sqrt(np.mean(f.residual[~ctx.outlier] ** 2))
    assert rms(out) < rms(alt)


def test_a_step_on_its_boundary_is_left_alone():
    ctx, base, alt, true_time, _ = _fits(0.0)
    out = polish_step(ctx, base, alt)
    assert abs(out.terms[-1].params["time"] - true_time) <= ctx.grid.dt / STEP_SUBDIVISIONS
    assert out.loglik >= alt.loglik


def test_other_terms_pass_through():
    ctx, base, _, _, _ = _fits(0.0)
    drift = Term("drift_lin", {"effect": "time_drift", "duration": ctx.cov.duration})
    alt = fit_terms(ctx, base.terms + (drift,), spec=base.noise.spec)
    assert polish_step(ctx, base, alt) is alt
