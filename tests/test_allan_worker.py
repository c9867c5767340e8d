"""A long record's allan_deviation runs the noise identification (and, without gaps, the
EDF) on a worker thread beside the variances. The result must equal the serial path's
exactly, and allantools' oadev (the independent reference), with and without gaps."""

from __future__ import annotations

import allantools
import numpy as np
import pytest

from fogbayes.stats import allan


@pytest.mark.parametrize("gaps", [False, True])
def test_worker_path_equals_the_serial_path(gaps, monkeypatch):
    n = allan.PARALLEL_NOISE_ID + 12_345  # long enough for the worker
    rng = np.random.default_rng(3)
    y = np.cumsum(rng.normal(size=n)) * 1e-3 + rng.normal(size=n) + 50.0
    if gaps:
        y[rng.integers(0, n, 40)] = np.nan
    res = allan.allan_deviation(y, 10.0, taus="octave")
    with monkeypatch.context() as mp:
        mp.setattr(allan, "PARALLEL_NOISE_ID", 1 << 40)  # everything on this thread
        serial = allan.allan_deviation(y, 10.0, taus="octave")
    for field in ("var", "n_terms", "alpha", "edf", "dev_low", "dev_high"):
        np.testing.assert_array_equal(getattr(res, field), getattr(serial, field), field)
    assert res.n_missing == int(np.isnan(y).sum())
    if not gaps:
        ref = allantools.oadev(y, rate=10.0, data_type="freq", taus=res.tau)
        np.testing.assert_allclose(res.dev, ref[1], rtol=1e-9)
