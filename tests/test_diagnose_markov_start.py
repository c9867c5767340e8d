"""The start of a Gauss-Markov component is the best point of its (tau_c, v) grid.

``markov_start`` evaluates the whole grid in one vmapped call (``nullsim.column_logliks``);
the reference here is the NumPy GLS profile (``noise_ssm.gls``) at every grid point, one
filter pass each.
"""

from __future__ import annotations

import math

import numpy as np

from fogbayes.loop import markov
from fogbayes.loop.context import make_context
from fogbayes.loop.fitting import fit_terms
from fogbayes.inference import noise_ssm as ns
from fogbayes.loop.bases import base_terms
from fogbayes.loop.testbed import make_record


def test_the_start_is_the_grid_point_of_largest_likelihood():
    rec = make_record(None, seed=2, duration=7200.0, fs=1.0).recording
    ctx = make_context(rec, target_blocks=400)
    fit = fit_terms(ctx, base_terms(ctx, "bias-t"))
    start = markov.markov_start(ctx, fit)
    taus, vs = markov._grid(ctx, fit.noise.spec)
    alt = fit.noise.spec._replace(n_markov=1)
    ll = np.array([[ns.gls(alt, markov._alt_theta(fit.noise.spec, fit.noise.theta,
                                                   math.log(v), math.log(t)),
                           ctx.y, fit.X, ctx.grid.mask, ctx.grid.w).loglik for v in vs]
                   for t in taus])
    it, iv = np.unravel_index(np.argmax(ll), ll.shape)
    assert start.params["tau"] == taus[it] and start.params["logvar"] == math.log(vs[iv])
