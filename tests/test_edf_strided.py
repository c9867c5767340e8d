"""Greenhall's basic sum beyond the exact range: the strided sum keeps every alpha's EDF.

Up to 2 000 terms the sum is exact (and equals allantools', tests/test_allan_references.py);
beyond, the integers around each kink of s_z are taken one by one and the stretches between
them as integrals (graded Gauss-Legendre, Euler-Maclaurin end correction). The reference here is the same sum taken exactly at every integer.
White phase (alpha = +2) is the hard case: its s_z is a spike of width 1/m at each integer,
which a plain stride of a few integers steps over (the EDF was off by up to 93 %).
"""

from __future__ import annotations

import numpy as np
import pytest

from fogbayes.stats import edf

MS = [2 ** 13, 2 ** 15, 2 ** 17, 30000, 250000]


@pytest.mark.parametrize("kind,alphas", [("oadev", (-2, -1, 0, 1, 2)), ("mdev", (-2, 0, 2)),
                                         ("ohdev", (-4, -3, -1, 1, 2))])
def test_strided_sum_matches_the_exact_sum(monkeypatch, kind, alphas):
    n = 1 << 20
    for a in alphas:
        got = edf.edf_for_kind([a] * len(MS), MS, n, kind)
        with monkeypatch.context() as mp:
            mp.setattr(edf, "_EXACT_TERMS", 10 ** 9)
            exact = edf.edf_for_kind([a] * len(MS), MS, n, kind)
        # measured worst 1.6e-6 (alpha = 1: t^2 ln|t| has the slowest-converging kinks)
        np.testing.assert_allclose(got, exact, rtol=1e-5, err_msg=f"{kind} alpha={a}")
