"""The bootstrap Bartlett factor (fogbayes.loop.bartlett) where the ratio is regular.

Under white noise (the noise model still has its flicker bank and walk, both fitted near
zero) nothing piles up: the refitted ratio of a term the record does not hold
is chi^2_dof, so the factor (mean of 20 simulated ratios / dof, floored at 1) must stay
near 1. With a fixed seed, the mean of 20 chi^2_1 draws exceeds 2 with probability ~0.005.
The walk case, where it must exceed 1, is in tests/test_loop_effects.py.

Given the decision it feeds, the factor is estimated sequentially (batches of 5 until the
decision is the same at +-2 standard errors, at most ``n_max``): a settled decision must
leave the first batch's factor unchanged, an open one must average every batch.
"""

from __future__ import annotations

import itertools

import numpy as np

from fogbayes.loop.bartlett import BATCH_SEED, bartlett_factor, in_walk_mode
from fogbayes.loop.candidates import candidates_for
from fogbayes.loop.context import make_context
from fogbayes.loop.fitting import fit_terms
from fogbayes.loop.bases import base_terms
from fogbayes.loop.testbed import make_record


def _white_record_with_drift():
    rec = make_record(None, seed=5, duration=10800.0, fs=1.0, noise="white").recording
    ctx = make_context(rec, target_blocks=600)
    base = fit_terms(ctx, base_terms(ctx, "bias-t"))
    drift = next(c for c in candidates_for(ctx, base.terms) if c.effect == "time_drift")
    alt = fit_terms(ctx, base.terms + tuple(drift.grid[:1]), spec=base.noise.spec)
    return ctx, base, alt


def test_the_factor_is_near_one_for_a_regular_ratio():
    ctx, base, alt = _white_record_with_drift()
    assert not in_walk_mode(base)
    c = bartlett_factor(ctx, base, alt, 1, n_sims=20, seed=3)
    assert 1.0 <= c < 2.0


def test_the_sequential_factor_stops_when_settled_and_averages_every_batch_when_open(
        monkeypatch):
    # Bookkeeping, not values: seeded stand-in ratios (the real ones are the test above),
    # so each batch's seed and the average over batches can be checked exactly.
    from fogbayes.loop import bartlett

    seeds = []

    def fake(ctx, base, alt, n_sims, *, seed):
        seeds.append(seed)
        return np.random.default_rng(seed).chisquare(1, n_sims) * 3.0

    monkeypatch.setattr(bartlett, "null_ratios", fake)
    kw = {"n_sims": 5, "seed": 3}
    first = bartlett.bartlett_factor(None, None, None, 1, **kw)
    assert seeds == [3]  # without a decision: one batch
    assert bartlett.bartlett_factor(None, None, None, 1, decide=lambda c: True, **kw) == first
    assert seeds == [3, 3]  # a settled decision: the first batch alone
    seeds.clear()
    flips = itertools.cycle([True, False])  # never the same at both ends: always open
    c = bartlett.bartlett_factor(None, None, None, 1, n_max=10, decide=lambda c: next(flips),
                                 **kw)
    assert seeds == [3, 3 + BATCH_SEED]  # two batches, the second seeded apart
    ratios = np.concatenate([fake(None, None, None, 5, seed=s) for s in list(seeds)])
    assert c == max(1.0, float(ratios.mean())) != first


def test_a_few_agreeing_ratios_cannot_settle_a_close_decision(monkeypatch):
    # Null ratios that all happen to be 0 have a sample standard error of 0; the factor's own
    # model (LR / c ~ chi^2_1, sd >= c sqrt(2)) keeps +-2 se at +-1.26 after 5 series, which
    # straddles a decision flipping at c = 1.2, and at +-0.89 after 10, which does not.
    from fogbayes.loop import bartlett

    calls = []

    def zeros(ctx, base, alt, n_sims, *, seed):
        calls.append(seed)
        return np.zeros(n_sims)

    monkeypatch.setattr(bartlett, "null_ratios", zeros)
    c = bartlett.bartlett_factor(None, None, None, 1, n_sims=5, decide=lambda c: c < 1.2)
    assert c == 1.0 and len(calls) == 2
    calls.clear()
    bartlett.bartlett_factor(None, None, None, 1, n_sims=5, decide=lambda c: c < 1.3)
    assert len(calls) == 1  # settled at once where the decision is far
