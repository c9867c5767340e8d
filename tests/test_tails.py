"""fogbayes.support.tails and the MCMC ranks give scipy.stats' numbers to the last bit (the
reference: scipy.stats itself, which fogbayes no longer imports on its everyday paths)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from fogbayes.support import tails
from fogbayes.stats.mcmc import _average_ranks

X = np.array([0.0, 1e-3, 0.1, 1.0, 2.37, 5.0, 30.0, 700.0, 1500.0, 3000.0])
P = np.array([1e-12, 1e-3, 0.05, 0.5, 0.8, 0.95, 0.999])


@pytest.mark.parametrize("df", [1, 2, 3, 7, 12.5, 7201])
def test_chi_square_tails_and_quantiles_are_scipy_stats(df):
    np.testing.assert_array_equal(tails.chi2_sf(X, df), stats.chi2.sf(X, df))
    np.testing.assert_array_equal(tails.chi2_logsf(X, df), stats.chi2.logsf(X, df))
    np.testing.assert_array_equal(tails.chi2_isf(P, df), stats.chi2.isf(P, df))
    np.testing.assert_array_equal(tails.chi2_ppf(P, df), stats.chi2.ppf(P, df))
    assert tails.chi2_ppf(0.5, df) == stats.chi2.median(df)


def test_normal_and_student_quantiles_are_scipy_stats():
    z = np.array([-40.0, -3.0, -0.5, 0.0, 0.5, 3.0, 40.0])
    np.testing.assert_array_equal(tails.norm_cdf(z), stats.norm.cdf(z))
    np.testing.assert_array_equal(tails.norm_sf(z), stats.norm.sf(z))
    np.testing.assert_array_equal(tails.norm_ppf(P), stats.norm.ppf(P))
    np.testing.assert_array_equal(tails.norm_isf(P), stats.norm.isf(P))
    for df in (1, 2, 5.5, 30, 1000):
        np.testing.assert_array_equal(tails.t_ppf(P, df), stats.t.ppf(P, df))


def test_average_ranks_are_rankdata_with_ties():
    rng = np.random.default_rng(0)
    for a in (rng.normal(size=1000), rng.integers(0, 5, size=200).astype(float),
              np.array([3.0, 1.0, 2.0, 2.0, 3.0, 3.0, 0.0]), np.array([1.0])):
        np.testing.assert_array_equal(_average_ranks(a), stats.rankdata(a, method="average"))
