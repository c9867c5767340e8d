"""fogbayes.stats.mcmc against ArviZ 0.23 (the reference it reproduces), on chains built to
reach every branch: independent, strongly autocorrelated (the monotone sequence acts),
chains that disagree (R-hat far above 1), ties and constant chains, odd draw counts."""

import warnings

import numpy as np
import pytest

az = pytest.importorskip("arviz")

from fogbayes.stats import mcmc  # noqa: E402


def _ar1(rng, chains, draws, phi, shift=0.0):
    x = np.empty((chains, draws))
    x[:, 0] = rng.standard_normal(chains)
    e = rng.standard_normal((chains, draws))
    for t in range(1, draws):
        x[:, t] = phi * x[:, t - 1] + e[:, t]
    return x + shift * np.arange(chains)[:, None]


def _cases():
    rng = np.random.default_rng(7)
    yield "independent", rng.standard_normal((2, 1000))
    yield "ar 0.9, 4 chains", _ar1(rng, 4, 600, 0.9)
    yield "ar 0.99", _ar1(rng, 2, 1500, 0.99)
    yield "antithetic", _ar1(rng, 2, 800, -0.6)
    yield "chains apart", _ar1(rng, 3, 500, 0.5, shift=2.0)
    yield "odd draws", rng.standard_normal((2, 1001))
    yield "ties", np.round(rng.standard_normal((2, 400)), 1)
    yield "heavy tails", rng.standard_t(2, (2, 700))
    yield "constant", np.full((2, 300), 3.0)


@pytest.mark.parametrize("name, draws", list(_cases()))
def test_every_diagnostic_is_arviz_s(name, draws):
    ours = {"rhat": mcmc.rhat_rank(draws), "bulk": mcmc.ess_bulk(draws),
            "tail": mcmc.ess_tail(draws), "mean": mcmc.ess_mean(draws)}
    with warnings.catch_warnings():  # ArviZ divides 0 by 0 on constant draws (NaN, as ours)
        warnings.simplefilter("ignore", RuntimeWarning)
        ref = {"rhat": az.rhat(draws, method="rank"), "bulk": az.ess(draws, method="bulk"),
               "tail": az.ess(draws, method="tail"), "mean": az.ess(draws, method="mean")}
    for key in ours:
        a, b = float(ours[key]), float(ref[key])
        if np.isnan(b):
            assert np.isnan(a), (name, key, a)
        else:
            assert a == pytest.approx(b, rel=1e-10, abs=1e-12), (name, key, a, b)


def test_over_elements_keeps_the_trailing_shape():
    rng = np.random.default_rng(1)
    draws = rng.standard_normal((2, 200, 3, 2))
    out = mcmc.over_elements(mcmc.ess_bulk, draws)
    assert out.shape == (3, 2)
    assert out[2, 1] == pytest.approx(mcmc.ess_bulk(draws[:, :, 2, 1]), rel=0)


def test_one_chain_has_no_rhat():
    assert np.isnan(mcmc.rhat_rank(np.random.default_rng(0).standard_normal((1, 100))))
