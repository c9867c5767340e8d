"""The calibration's constant is the IEEE 952 bias: a calibration run compensated by its own
loop document averages to zero, and the constant's standard error is the scatter of that
estimator under the fitted noise model (fogbayes/loop/constant.py)."""

from __future__ import annotations

import json

import jax.numpy as jnp
import numpy as np
import pandas as pd
import pytest

import fogbayes.cli as cli
from fogbayes.data import save
from fogbayes.loop.context import make_context
from fogbayes.loop.fitting import fit_terms
from fogbayes.loop.nullsim import simulate
from fogbayes.inference import noise_ssm as ns
from fogbayes.loop.bases import base_terms
from fogbayes.loop.constant import ieee_constant, mean_variance
from fogbayes.loop.testbed import make_record


def _dense_cov(phi, q, p0, w):
    """Covariance of the state-space noise written out entry by entry (independent of the
    O(n) recursion): x_t = phi^t x_0 + sum_{s<t} phi^(t-1-s) e_s."""
    n = w.size
    S = np.diag(w).astype(float)
    i = np.arange(n)
    for ph, qj, pj in zip(phi, q, p0):
        C = pj * np.power(ph, i[:, None] + i[None, :])
        for a in range(n):
            for b in range(n):
                s = np.arange(min(a, b))
                C[a, b] += qj * np.sum(np.power(ph, a - 1 - s) * np.power(ph, b - 1 - s))
        S += C
    return S


def test_mean_variance_is_u_S_u_of_the_dense_covariance():
    n = 40
    spec = ns.make_spec(10.0, 400.0, n_markov=1, random_walk=True)
    rng = np.random.default_rng(5)
    lo, hi = np.array(ns.bounds(spec)).T
    theta = lo + (hi - lo) * rng.uniform(0.3, 0.7, size=lo.size)
    w = rng.uniform(1.0, 2.0, n)
    u = rng.uniform(0.5, 1.5, n)
    u[[3, 17]] = 0.0  # missing blocks carry no weight
    u /= u.sum()
    phi, q, p0 = (np.asarray(a) for a in ns.system(spec, ns.unpack(spec, jnp.asarray(theta))))
    want = u @ _dense_cov(phi, q, p0, w) @ u
    np.testing.assert_allclose(mean_variance(spec, theta, w, u), want, rtol=1e-10)


@pytest.fixture(scope="module")
def record(tmp_path_factory):
    d = tmp_path_factory.mktemp("const")
    rec = make_record("temperature_rate", seed=3, duration=2400.0, fs=1.0).recording
    save(rec, d / "rec.csv")
    return d, rec


def test_a_calibration_run_compensated_by_its_own_loop_averages_to_zero(record):
    d, rec = record
    ctx = make_context(rec)
    gls = fit_terms(ctx, base_terms(ctx, "bias-t", "2"))
    used = ctx.grid.use
    # the GLS intercept (the random walk's starting level) leaves a material mean here
    assert abs(np.mean(gls.residual[used])) > 0.05 * np.std(gls.residual[used])
    assert cli.main(["-q", "loop", str(d / "rec.csv"), "-m", "bias-t", "--max-steps", "0",
                     "--json", str(d / "l.json"), "--compensated", str(d / "c.csv")]) == 0
    comp = pd.read_csv(d / "c.csv")
    out = comp["output"][~comp["outlier"].astype(bool)]
    assert abs(out.mean()) < 1e-9 * out.std()
    # compensate with the document gives the same zero-mean output on the same run
    assert cli.main(["-q", "compensate", str(d / "rec.csv"), "--params", str(d / "l.json"),
                     "--out", str(d / "c2.csv")]) == 0
    again = pd.read_csv(d / "c2.csv")
    np.testing.assert_allclose(again["output"], comp["output"], rtol=0, atol=1e-9)
    cal = json.loads((d / "l.json").read_text())["calibration"]
    assert cal["terms"][0]["kind"] == "intercept"
    assert cal["stderr"][0] >= np.sqrt(gls.noise.cov_beta[0, 0])


def test_the_constants_stderr_is_its_scatter_under_the_noise_model(record):
    """Monte Carlo under the fitted noise (hyperparameters fixed, as the stderr assumes):
    400 series give the estimator's sd to +-3.5 %; the tolerance is 12 % (3.4 se)."""
    _, rec = record
    ctx = make_context(rec)
    fit = fit_terms(ctx, base_terms(ctx, "bias-t", "2"))
    nf = fit.noise
    se = np.sqrt(ieee_constant(ctx, fit).noise.cov_beta[0, 0])
    m = 400
    e = simulate(nf.spec, nf.theta, nf.sigma2, ctx.grid.w, m, seed=11)
    mask = ctx.grid.mask
    Y = (fit.X @ nf.beta)[:, None] + e
    V, F = ns.filter_padded(nf.spec, nf.theta, np.column_stack([Y * mask[:, None], fit.X]),
                            mask, ctx.grid.w)
    g = mask / F
    VX, VY = V[:, m:], V[:, :m]
    B = np.linalg.solve((VX * g[:, None]).T @ VX, (VX * g[:, None]).T @ VY)  # (p, m)
    u = ctx.grid.count * mask
    u = u / u.sum()
    c = B[0] + u @ (Y - fit.X @ B)
    sd = np.std(c, ddof=1)
    assert sd == pytest.approx(se, rel=0.12)
    # the GLS intercept's own stderr misses the time average's scatter
    assert np.sqrt(nf.cov_beta[0, 0]) < 0.5 * sd
