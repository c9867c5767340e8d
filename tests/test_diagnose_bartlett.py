"""The bootstrap Bartlett factor (fogbayes.diagnose.bartlett) where the ratio is regular.

Under white noise (the noise model still has its flicker bank and walk, both fitted near
zero) nothing piles up: the refitted ratio of a term the record does not hold
is chi^2_dof, so the factor (mean of 20 simulated ratios / dof, floored at 1) must stay
near 1. With a fixed seed, the mean of 20 chi^2_1 draws exceeds 2 with probability ~0.005.
The walk case, where it must exceed 1, is in tests/test_loop_effects.py.
"""

from __future__ import annotations

from fogbayes.diagnose.bartlett import bartlett_factor, in_walk_mode
from fogbayes.diagnose.candidates import candidates_for
from fogbayes.diagnose.context import make_context
from fogbayes.diagnose.fitting import fit_terms
from fogbayes.loop.bases import base_terms
from fogbayes.loop.testbed import make_record


def test_the_factor_is_near_one_for_a_regular_ratio():
    rec = make_record(None, seed=5, duration=10800.0, fs=1.0, noise="white").recording
    ctx = make_context(rec, target_blocks=600)
    base = fit_terms(ctx, base_terms(ctx, "bias-t"))
    drift = [c for c in candidates_for(ctx, base.terms) if c.effect == "time_drift"][0]
    alt = fit_terms(ctx, base.terms + tuple(drift.grid[:1]), spec=base.noise.spec)
    assert not in_walk_mode(base)
    c = bartlett_factor(ctx, base, alt, 1, seed=3)
    assert 1.0 <= c < 2.0
