"""The loop never ends worse than the plain fit (fogbayes.loop.plain_check): when its final
model predicts held-out time blocks worse than ``fogbayes fit``'s terms, the calibration
takes the plain base (with the loop's terms where they still help) instead."""

from __future__ import annotations

import numpy as np
import pytest

from fogbayes.diagnose.fitting import predict
from fogbayes.loop.core import run_loop
from fogbayes.loop.plain_check import PLAIN_TOLERANCE_NATS
from fogbayes.loop.testbed import make_record


def _error(res, truth) -> float:
    """RMS of (fitted deterministic model - truth) over the record, mean removed."""
    e = predict(res.fit, res.context.cov) - truth
    return float(np.sqrt(np.mean((e - e.mean()) ** 2)))


@pytest.fixture(scope="module")
def cubic():
    # a cubic in T three times the testbed's size; the loop may only add a step, so its
    # order-2 base cannot follow the cubic while the plain fit's order 3 can
    tr = make_record("temperature_order", seed=5, duration=3600.0, fs=1.0, magnitude=3.0)
    res = run_loop(tr.recording, "bias-t", max_steps=1, effects=("step",), n_sims=100)
    return tr, res


def test_a_loop_model_worse_than_the_plain_fit_is_replaced(cubic):
    tr, res = cubic
    h = res.holdout
    assert h["replaced_by"] in ("plain base with the loop's terms", "plain base by GLS")
    assert h["lpd_loop_model"] < h["lpd_plain_fit"] - PLAIN_TOLERANCE_NATS
    assert h["final_not_worse_than_plain_fit"] is True
    assert h["lpd_final"] >= h["lpd_plain_fit"] - PLAIN_TOLERANCE_NATS
    assert any("calibration uses the" in w for w in res.warnings)
    # the calibration carries the cubic power now, and follows the truth better than the
    # loop's own base did (the truth: the testbed's quadratic + the planted cubic)
    truth = sum(tr.effects.values())
    base_only = res._replace(fit=res.initial_fit)
    assert _error(res, truth) < 0.5 * _error(base_only, truth)
    powers = [p for t in res.fit.terms if t.kind == "tpoly" for p in t.params["powers"]]
    assert 3 in powers


def test_a_loop_model_as_good_as_the_plain_fit_is_kept():
    # the declared quadratic only: the loop's order-2 base is the true form
    tr = make_record(None, seed=5, duration=3600.0, fs=1.0)
    res = run_loop(tr.recording, "bias-t", max_steps=1, effects=("step",), n_sims=100)
    assert res.holdout["final_not_worse_than_plain_fit"] is True
    assert "replaced_by" not in res.holdout
    assert res.fit.terms == res.initial_fit.terms
