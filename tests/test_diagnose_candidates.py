"""Candidate library, terms and covariates of fogbayes.loop."""

from __future__ import annotations

import numpy as np
import pytest

from fogbayes.data import Metadata, Recording
from fogbayes.loop.candidates import EFFECTS, candidates_for
from fogbayes.loop.context import make_context, spike_flags
from fogbayes.preprocess.covariates import block_grid
from fogbayes.effects.terms import Term, columns, first_order_lag
from fogbayes.loop.bases import base_terms
from fogbayes.loop.testbed import make_record
from fogbayes.simulate.profiles import first_order_lag as sim_lag


def test_lag_matches_the_simulator_on_a_uniform_grid():
    t = np.arange(0.0, 4000.0, 0.5)
    u = np.sin(t / 300.0) + 0.01 * t
    # Both are the exact ramp-invariant discretisation: equal to rounding.
    np.testing.assert_allclose(first_order_lag(t, u, 120.0), sim_lag(t, u, 120.0), atol=1e-12)


def test_lag_on_irregular_times_matches_a_fine_uniform_reference():
    rng = np.random.default_rng(0)
    t = np.sort(rng.uniform(0.0, 3000.0, 4000))
    u = np.sin(t / 300.0)
    fine = np.linspace(0.0, 3000.0, 300001)
    ref = np.interp(t, fine, sim_lag(fine, np.interp(fine, t, u), 120.0))
    # The reference sees u linear between the irregular samples too, so only the fine
    # grid's interpolation error (~1e-9) separates them.
    np.testing.assert_allclose(first_order_lag(t, u, 120.0), ref, atol=1e-7)


def test_a_lag_of_one_sensor_at_the_other_sensors_time_constant_is_the_gradient():
    # Two sensors lagging one chamber temperature u by tau1 and tau2 (the simulator's
    # thermal scenarios): partial fractions, 1/((1+tau2 s)(1+tau1 s)) =
    # (tau2/(1+tau2 s) - tau1/(1+tau1 s)) / (tau2 - tau1), give
    #     L_tau2[T1] = (tau2 T2 - tau1 T1) / (tau2 - tau1),   T1 = L_tau1[u], T2 = L_tau2[u],
    # so with T1 in the model, thermal_lag (tau = tau2) and temperature_gradient (T2 - T1)
    # span the same space: on such records the two effects cannot be told apart.
    t = np.arange(0.0, 20000.0, 0.5)
    u = np.interp(t, [0, 3000, 7000, 9000, 14000, 20000], [20, 20, 60, 60, -20, -20])
    tau1, tau2 = 300.0, 900.0
    T1, T2 = sim_lag(t, u, tau1), sim_lag(t, u, tau2)
    closed = (tau2 * T2 - tau1 * T1) / (tau2 - tau1)
    # T1 is not linear between samples: the ramp-invariant recursion is then O(h^2 / tau)
    np.testing.assert_allclose(first_order_lag(t, T1, tau2), closed, atol=1e-5)


def test_every_design_effect_has_a_candidate():
    thermal = make_context(make_record(None, seed=0, duration=3600.0, fs=1.0).recording)
    table = make_context(make_record(None, seed=0, duration=3600.0, fs=1.0,
                                     profile="ratetable").recording)
    names = {c.effect for c in candidates_for(thermal, base_terms(thermal, "bias-t"))}
    names |= {c.effect for c in candidates_for(table, base_terms(table, "composite"))}
    assert names == set(EFFECTS) - {"markov_noise"}  # a noise component: loop/noise_model.py


def test_candidates_drop_what_the_model_already_has():
    ctx = make_context(make_record(None, seed=0, duration=3600.0, fs=1.0).recording)
    names = {c.effect for c in candidates_for(ctx, base_terms(ctx, "thermal"))}
    assert "temperature_rate" not in names and "temperature_order" in names


def test_temperature_rate_of_a_ramp_is_its_slope():
    t = np.arange(0.0, 1800.0, 0.5)
    T = 20.0 + 0.5 / 60.0 * t  # 0.5 deg C/min
    rec = Recording(time=t, output=np.zeros(t.size), temperatures=T[:, None],
                    meta=Metadata(sample_rate=2.0))
    ctx = make_context(rec)
    # Savitzky-Golay order 2 is exact on a line, away from nothing (mode="interp").
    np.testing.assert_allclose(ctx.cov.Tdot, 0.5, rtol=1e-9)


def test_block_grid_keeps_bursts_and_marks_gaps_missing():
    t = np.concatenate([np.arange(0.0, 5.0, 0.02), np.arange(300.0, 305.0, 0.02)])
    g = block_grid(t, 50.0, target_blocks=1000)
    assert g.dt == pytest.approx(0.32)  # 16 whole samples: 305 s / 1000 blocks rounded up
    assert g.count.sum() == t.size
    assert g.mask.sum() == np.unique(g.index).size == 33  # 16 + 17 blocks (grid offset)
    assert not g.mask[20:930].any()  # between the bursts: missing, never filled
    x = np.arange(t.size, dtype=float)
    b = g.mean(x)
    k = np.flatnonzero(g.mask)[0]
    assert b[k] == pytest.approx(np.mean(x[g.index == k]))


def test_terms_are_centred_and_scaled():
    ctx = make_context(make_record(None, seed=1, duration=3600.0, fs=1.0).recording)
    X = np.column_stack([columns(tm, ctx.cov) for tm in base_terms(ctx, "bias-t")])
    assert X.shape == (ctx.cov.t.size, 4)  # constant, T', T'^2, T'^3
    assert np.max(np.abs(X[:, 1])) == pytest.approx(1.0, abs=0.05)  # T' spans [-1, 1]
    per = columns(Term("periodic", {"frequency": 0.01}), ctx.cov)
    np.testing.assert_allclose(per[:, 0] ** 2 + per[:, 1] ** 2, 1.0)


def test_spike_flags_find_isolated_spikes_not_steps():
    x = np.random.default_rng(2).standard_normal(5000)
    x[1000] += 50.0
    x[3000:] += 30.0  # a level step is an effect, not an outlier
    flags = spike_flags(x)
    assert flags[1000] and flags.sum() == 1


def test_a_step_is_searched_at_every_block_boundary():
    """Under flicker-dominated noise a step's statistic peaks over ~3 blocks: a coarse time
    grid (300 times, 170 s apart here) put this 0.2 deg/h step at 27 160 s; the truth is
    26 400 s (thermal base, paper 004's programme at 1 Hz, 5280 blocks of 10 s)."""
    from fogbayes.loop import evidence as ev
    from fogbayes.loop.fitting import fit_terms
    from fogbayes.loop.reml import with_reml
    from fogbayes.inference import noise_fit as nfit
    from fogbayes.simulate import simulate

    sim = simulate("paper004", seed=1, effects={"step": {}})
    ctx = make_context(sim.recording)
    fit = fit_terms(ctx, base_terms(ctx, "thermal"))
    step = [c for c in candidates_for(ctx, fit.terms) if c.effect == "step"][0]
    times = np.array([t.params["time"] for t in step.grid])
    assert np.allclose(np.diff(times), ctx.grid.dt)  # every block boundary
    nf = nfit.fit_noise(fit.noise.spec._replace(random_walk=False), ctx.y, fit.X,
                        ctx.grid.mask, ctx.grid.w)  # the walk-free look of the loop
    _, (s,) = ev.screen(ctx, with_reml(ctx, fit._replace(noise=nf), {}), [step], n_sims=100,
                        seed=0)
    true = sim.truth.params["effects"]["step"]["time"]
    assert abs(s.best_value - true) <= 2 * ctx.grid.dt
