"""Time-blocked cross-validation of the loop (fogbayes.loop.holdout) and the noise model
chosen apart from the effects (fogbayes.loop.noise_model)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fogbayes.loop.context import make_context
from fogbayes.loop.fitting import fit_terms
from fogbayes.effects.terms import Term
from fogbayes.loop import holdout
from fogbayes.loop.bases import base_terms
from fogbayes.loop.testbed import make_record


def test_white_noise_score_is_the_closed_form():
    """Under white noise alone the fold's predictive density is a product of normals about
    the weighted least-squares prediction from the other folds (independent NumPy)."""
    from fogbayes.inference import noise_ssm as ns

    tr = make_record("step", seed=4, duration=3600.0, fs=2.0, noise="white")
    ctx = make_context(tr.recording, target_blocks=400, random_walk=False, flicker=False)
    base = base_terms(ctx, "bias-t")
    # the state-space model needs a state: one Gauss-Markov component of variance e^-50
    spec = ctx.spec._replace(n_markov=1)
    fit = fit_terms(ctx, base + [Term("step", {"time": 1800.0})], spec=spec)
    theta = ns.pack(spec, ns.NoiseParams(-60.0, -60.0, np.array([-50.0]), np.array([4.0])))
    s2 = 0.7 * float(fit.noise.sigma2)  # any fixed scale: the score holds it fixed
    fit = fit._replace(noise=fit.noise._replace(spec=spec, theta=theta, sigma2=s2))
    got = holdout.score(ctx, fit)
    obs = ctx.grid.mask > 0
    fid = holdout.folds(ctx)
    want = 0.0
    for j in range(holdout.N_FOLDS):
        held, train = obs & (fid == j), obs & (fid != j)
        W = 1.0 / ctx.grid.w[train]
        Xt, yt = fit.X[train], ctx.y[train]
        beta = np.linalg.solve(Xt.T @ (W[:, None] * Xt), Xt.T @ (W * yt))
        r = ctx.y[held] - fit.X[held] @ beta
        v = s2 * ctx.grid.w[held]
        want += float(np.sum(-0.5 * np.log(2 * math.pi * v) - 0.5 * r * r / v))
    assert got.lpd == pytest.approx(want, rel=1e-9, abs=1e-6)
    assert np.all(np.bincount(fid[obs]) >= obs.sum() // holdout.N_FOLDS)  # equal folds


def test_a_real_step_predicts_held_out_folds_and_a_spurious_one_does_not():
    """Random-walk + flicker noise (the loop's default model): the planted step at its time
    gains held-out density; a step placed where nothing happened loses it."""
    tr = make_record("step", seed=2, duration=3 * 3600.0, fs=2.0, magnitude=3.0)
    t_step = tr.effect_params["time"]
    ctx = make_context(tr.recording, target_blocks=900)
    base = base_terms(ctx, "bias-t")
    h0 = holdout.score(ctx, fit_terms(ctx, base))
    h_true = holdout.score(ctx, fit_terms(ctx, base + [Term("step", {"time": t_step})]))
    h_false = holdout.score(ctx, fit_terms(ctx, base + [Term("step", {"time": 0.25 * t_step})]))
    assert h_true.lpd > h0.lpd + 5.0
    c = holdout.compare(h_true, h0)
    assert c.kept and c.folds >= 8  # a mid-record step is judged by (nearly) every fold
    assert h_false.lpd < h_true.lpd


def test_loop_document_reports_the_noise_model_and_the_holdout():
    from fogbayes.loop import run_loop

    tr = make_record("step", seed=2, duration=3 * 3600.0, fs=2.0, magnitude=3.0)
    res = run_loop(tr.recording, "bias-t", seed=2, max_steps=2, n_sims=200, target_blocks=900)
    doc = res.to_json()
    assert res.effects[:1] == ["step"]
    assert "markov_noise" not in res.effects  # noise is never a step
    h = doc["holdout"]
    assert h["folds"] == holdout.N_FOLDS and h["lpd_final"] >= h["lpd_base"]
    assert doc["steps"][0]["evidence"]["holdout"]["kept"] is True
    assert isinstance(doc["noise_model"]["components"], list)
    assert doc["calibration"]["noise"]["gauss_markov_components"] == len(
        doc["noise_model"]["components"])


def test_a_fold_holding_all_of_a_warm_up_does_not_judge_it():
    """A 300 s warm-up lives in the first of ten 1080 s folds: without that fold its
    amplitude is unidentified (e^-1080/300 ~ 3 % left), so that fold cannot judge it and is
    left out of the comparison; the other nine do."""
    tr = make_record("time_drift", seed=5, duration=3 * 3600.0, fs=2.0,
                     effect_params={"amplitude": 2.0, "tau": 300.0})
    ctx = make_context(tr.recording, target_blocks=900)
    base = base_terms(ctx, "bias-t")
    h0 = holdout.score(ctx, fit_terms(ctx, base))
    h1 = holdout.score(ctx, fit_terms(ctx, base + [Term("drift_exp", {"tau": 300.0})]))
    new = h1.info[:, -1]
    assert new[0] < holdout.MIN_INFORMATION <= new[1:].min()
    c = holdout.compare(h1, h0)
    assert c.folds == holdout.N_FOLDS - 1
    assert c.lpd_before == pytest.approx(h0.per_fold[1:].sum())


def test_compare_keeps_a_term_only_if_not_worse_and_reports_the_scatter():
    """Paired fold differences d_k: a sum of -0.5 is worse (not kept, however large the
    folds' scatter, which is reported as se = sqrt(K var d)); +0.5 is kept; the columns
    beyond the model without the term decide which folds judge it."""
    K = holdout.N_FOLDS
    base = holdout.Holdout(0.0, np.zeros(K), 100, np.ones((K, 2)))

    def with_d(d, info_new=1.0):
        info = np.column_stack([np.ones((K, 2)), np.full(K, info_new)])
        return holdout.Holdout(float(np.sum(d)), np.asarray(d, float), 100, info)

    noisy = np.array([3.0, -3.0, 2.0, -2.0, 2.5, -2.5, 1.0, -1.0, 0.5, -1.0])
    c = holdout.compare(with_d(noisy), base)
    assert not c.kept and c.lpd - c.lpd_before == pytest.approx(-0.5)
    assert c.se == pytest.approx(np.sqrt(K * np.var(noisy, ddof=1)))
    assert holdout.compare(with_d(noisy + 0.1), base).kept  # sum +0.5
    uninformed = with_d(noisy, info_new=0.01)  # no fold can judge the new coefficient
    assert holdout.compare(uninformed, base).folds == 0 and holdout.compare(uninformed, base).kept
