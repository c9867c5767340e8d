"""A long record's octave oadev on two threads: the pyramid's short taus here, the longest
by the phase window on the worker. Same estimator: the result must equal one pyramid's (to
rounding) and allantools' oadev, with and without gaps."""

from __future__ import annotations

import allantools
import numpy as np
import pytest

from fogbayes.stats import allan
from fogbayes.stats.allan_blocked import allan_variance_fast


@pytest.mark.parametrize("gaps", [False, True])
def test_two_thread_oadev_equals_one_pyramid(gaps):
    n = allan.PARALLEL_NOISE_ID + 12_345  # long enough for the worker
    rng = np.random.default_rng(3)
    y = np.cumsum(rng.normal(size=n)) * 1e-3 + rng.normal(size=n) + 50.0
    if gaps:
        y[rng.integers(0, n, 40)] = np.nan
    res = allan.allan_deviation(y, 10.0, taus="octave")
    var, count = allan_variance_fast(y, tuple(res.m))  # all levels by one pyramid
    np.testing.assert_allclose(res.var, var, rtol=1e-12)
    np.testing.assert_array_equal(res.n_terms, count)
    if not gaps:  # allantools as the independent reference
        ref = allantools.oadev(y, rate=10.0, data_type="freq", taus=res.tau)
        np.testing.assert_allclose(res.dev, ref[1], rtol=1e-9)
