"""The closed loop on a rate table and on noise terms (the CI-sized subset of the study).

Split from tests/test_loop_effects.py (same criteria) to keep each file under a minute:
a scale-factor effect on the ``composite`` base, and ``markov_noise`` on the ``allan`` base.
"""

from __future__ import annotations

import numpy as np

from fogbayes.loop.fitting import fit_terms
from fogbayes.loop import run_loop
from fogbayes.loop.bases import base_terms
from fogbayes.loop.metrics import block_rms
from fogbayes.loop.testbed import make_record, oracle_terms

RUN = {"max_steps": 1, "n_sims": 200, "target_blocks": 900}  # as tests/test_loop_effects.py


def _oracle_rms(res, effect, params, model):
    """10 s-block RMS of the true model fitted the way the loop fits its own."""
    ctx = res.context
    fit = fit_terms(ctx, oracle_terms(ctx, base_terms(ctx, model), effect, params))
    return block_rms(ctx.cov.t, fit.residual, ctx.outlier)


def test_scale_factor_asymmetry_on_the_rate_table():
    tr = make_record("scale_factor_asymmetry", seed=9, duration=3600.0, fs=2.0, magnitude=0.05,
                     profile="ratetable")
    res = run_loop(tr.recording, "composite", seed=9, **RUN)
    assert res.effects[:1] == ["scale_factor_asymmetry"]
    oracle = _oracle_rms(res, "scale_factor_asymmetry", tr.effect_params, "composite")
    assert res.final.rms <= 1.10 * oracle  # the study's criterion
    assert res.final.rms < res.initial.rms


def test_markov_noise_on_the_allan_model():
    from fogbayes.data import Metadata, Recording
    from fogbayes.simulate.noise import allan_noise, markov_noise

    fs, n = 2.0, 21600
    x = allan_noise(n, fs, seed=3, N=0.003, B=0.02) + markov_noise(n, fs, seed=3, sigma=0.2,
                                                                    tau_c=200.0)
    rec = Recording(time=np.arange(n) / fs, output=x, meta=Metadata(sample_rate=fs))
    res = run_loop(rec, "allan", seed=0, **RUN)
    assert res.effects == []  # noise is modelled, never a step
    nm = res.to_json()["noise_model"]
    assert len(nm["components"]) == 1 and nm["selection"][0]["action"] == "added"
    d = nm["components"][0]
    # tau_c and sigma come back within a factor 2 (3 h hold ~50 correlation times)
    assert 100.0 < d["tau_c_s"] < 400.0 and 0.1 < d["sigma_deg_h"] < 0.4
    assert nm["adev_misfit"]["with_components"] < nm["adev_misfit"]["five_term"]


