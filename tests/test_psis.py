"""fogbayes.stats.psis against ArviZ 0.23's az.loo / az.waic (the independent reference).

The module claims ArviZ's arithmetic for one chain of draws (relative efficiency 1): every
pointwise elpd, Pareto k, the sums, standard errors, effective numbers of parameters and
both warnings, on records that take each path -- a regular tail, ties at the cut-off, weights
that underflow (a tail shorter than M), tails too short to fit (S <= 20) and heavy tails
(k > 0.7).
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import arviz

from fogbayes.inference.compare import information, loglik_idata
from fogbayes.stats import psis


def _records():
    rng = np.random.default_rng(20261205)
    for case in range(36):
        S = (100, 400, 30, 20, 10, 1000)[case % 6]
        n = (50, 200, 7)[case % 3]
        ll = rng.standard_normal((S, n)) * rng.uniform(0.1, 5) + rng.standard_normal(n)
        if case % 5 == 0:
            ll[:, :3] = np.round(ll[:, :3], 1)  # ties at the cut-off
        if case % 7 == 0:
            ll[:, 0] = np.linspace(0.0, 100.0 * S, S)  # weights below exp(-708): a short tail
        if case % 4 == 0:
            ll += 3 * rng.standard_t(1.5, (S, n))  # heavy tails: k beyond 0.7
        yield case, ll


@pytest.mark.parametrize("case, ll", list(_records()), ids=lambda v: str(v) if isinstance(
    v, int) else "")
def test_loo_and_waic_are_arviz_arithmetic(case, ll):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ref = {k: information(loglik_idata(ll), k) for k in ("loo", "waic")}
    for kind in ("loo", "waic"):
        ours, az = information(ll, kind), ref[kind]
        assert ours.data is None and az.data is not None
        np.testing.assert_array_equal(np.isnan(ours.pointwise), np.isnan(az.pointwise))
        np.testing.assert_allclose(ours.pointwise, az.pointwise, rtol=1e-11, atol=1e-11)
        for f in ("elpd", "se", "p"):
            np.testing.assert_allclose(getattr(ours, f), getattr(az, f), rtol=1e-11,
                                       atol=1e-11, err_msg=f"{kind} {f}")
        assert ours.warning == az.warning
    k = psis.loo(ll).pareto_k
    k_az = np.asarray(ref["loo"].data.pareto_k)
    np.testing.assert_array_equal(np.isfinite(k), np.isfinite(k_az))
    np.testing.assert_allclose(k[np.isfinite(k)], k_az[np.isfinite(k_az)], rtol=1e-11, atol=1e-12)


@pytest.mark.parametrize("case, ll", list(_records())[:12], ids=lambda v: str(v) if isinstance(
    v, int) else "")
def test_smoothed_weights_are_arviz_psislw_in_the_original_order(case, ll):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ref_w, ref_k = (np.asarray(a) for a in arviz.psislw(-ll.T))
    w, k = psis.psislw(-ll.T)
    np.testing.assert_array_equal(np.isfinite(k), np.isfinite(ref_k))
    np.testing.assert_allclose(k[np.isfinite(k)], ref_k[np.isfinite(ref_k)], rtol=1e-11,
                               atol=1e-12)
    # tied ratios share their smoothed weights in whichever order a sort leaves them (ArviZ's
    # own order of ties is its sort's): the weights of each row as a set, and in place on
    # rows without ties
    np.testing.assert_allclose(np.sort(w, axis=1), np.sort(ref_w, axis=1), rtol=1e-11,
                               atol=1e-11)
    untied = np.array([np.unique(r).size == r.size for r in -ll.T])
    assert untied.sum() >= 0.5 * untied.size
    np.testing.assert_allclose(w[untied], ref_w[untied], rtol=1e-11, atol=1e-11)


def test_the_records_reach_every_path():
    """The cases above are not all regular: each special path is taken at least once."""
    seen = set()
    for _, ll in _records():
        S = ll.shape[0]
        x = np.sort(-ll.T, axis=1)
        x -= x[:, -1:]
        m = psis._tail_length(S)
        cut = np.maximum(x[:, S - m - 1], psis._TINY_LOG)
        n_tail = np.sum(x > cut[:, None], axis=1)
        k = psis.loo(ll).pareto_k
        seen |= {"short tail"} if m <= 4 else set()
        under = x[:, S - m - 1] < psis._TINY_LOG
        seen |= {"tie"} if np.any((n_tail < m) & ~under) else set()
        seen |= {"underflow"} if np.any(under & (n_tail > 4)) else set()
        seen |= {"k > 0.7"} if np.any(k[np.isfinite(k)] > 0.7) else set()
    assert {"short tail", "tie", "underflow", "k > 0.7"} <= seen, seen


def test_unknown_criterion_is_refused():
    with pytest.raises(ValueError, match="loo"):
        information(np.zeros((10, 3)), "aic")
