"""A unit's covariance for the pool: resolved terms conditioned on the unresolved ones.

Closed forms: for a resolved N correlated (rho) with an unresolved Q, the conditioned
variance is sigma_N^2 (1 - rho^2), the Schur complement; with nothing unresolved the
covariance is the fit's own. The simulated fleet's unit that first showed the effect
(``benchmarks/pool_allan_units.py``, unit 100) now resolves Q: its width came from GLS
weights that cycled (fogbayes.allan.fit._reweighted).
"""

from __future__ import annotations

import numpy as np
import pytest

from fogbayes.allan.model import TERMS
from fogbayes.pool.allan import UnitFit, resolved_covariance


class _Term:
    def __init__(self, low):
        self.low = low


def _unit(cov, unresolved=()):
    terms = {t: _Term(0.0 if t in unresolved else 1.0) for t in TERMS}
    return UnitFit("u", None, 1000, 10.0, np.zeros(5), np.asarray(cov, float), terms, 0, 0.5,
                   True)


def _cov(sd, corr):
    sd = np.asarray(sd, float)
    return np.outer(sd, sd) * np.asarray(corr, float)


def test_the_resolved_terms_are_the_schur_complement_of_the_unresolved():
    rng = np.random.default_rng(0)
    a = rng.normal(size=(5, 5))
    cov = a @ a.T + 0.1 * np.eye(5)
    got = resolved_covariance(_unit(cov, unresolved=("Q", "K")))
    r, c = [1, 2, 4], [0, 3]
    schur = cov[np.ix_(r, r)] - cov[np.ix_(r, c)] @ np.linalg.inv(cov[np.ix_(c, c)]) @ cov[np.ix_(c, r)]
    np.testing.assert_allclose(got[np.ix_(r, r)], schur, rtol=1e-12)
    np.testing.assert_array_equal(np.diag(got)[c], np.diag(cov)[c])  # own variance kept
    assert not got[np.ix_(r, c)].any() and got[0, 3] == 0.0           # and no covariance


def test_two_terms_closed_form_and_nothing_unresolved_is_the_fit_itself():
    corr = np.eye(5)
    corr[0, 1] = corr[1, 0] = -0.95  # Q and N at the shortest taus
    cov = _cov([0.6, 0.2, 0.15, 5.0, 0.4], corr)
    got = resolved_covariance(_unit(cov, unresolved=("Q",)))
    assert got[1, 1] == pytest.approx(0.2 ** 2 * (1 - 0.95 ** 2), rel=1e-12)
    np.testing.assert_array_equal(resolved_covariance(_unit(cov)), cov)


def test_a_unit_whose_gls_weights_cycled_keeps_its_n():
    # Unit 100 of benchmarks/pool_allan_units.py (repetition 5, unit 0; N off by 3.4 %) was
    # the example of an unresolved Q widening N: marginal log sd 0.22. Its GLS weights cycle
    # (K- and R-dominated solutions); after 3 passes the fit had stopped on the solution
    # under which Q, K and R were all unresolved. The likelier pass end resolves Q, and N's
    # log sd is 0.007 with or without conditioning.
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
    import bench_pool as bp  # the fleets' simulator and single-unit fit

    rng = np.random.default_rng(10_005)  # repetition 5, unit 0 of bench_pool.py
    truth = [bp.unit_truth(rng) for _ in range(20)][0]
    unit = bp.fit_record(bp.simulate(truth, 2 ** 17, seed=500_000), "u0")
    assert unit.terms["Q"].low > 0.0 and unit.gof_p > 0.01
    n = TERMS.index("N")
    marginal = np.sqrt(unit.cov[n, n])
    conditioned = np.sqrt(resolved_covariance(unit)[n, n])
    assert marginal < 0.02 and conditioned <= marginal   # was 0.22 and 0.053
    assert abs(np.log(unit.terms["N"].value / truth["N"])) < 1.645 * conditioned  # covers


def test_the_pool_warns_of_a_unit_whose_five_term_fit_fails():
    from fogbayes.pool.allan import check_units

    good = _unit(np.eye(5))
    bad = _unit(np.eye(5))._replace(name="u7", gof_p=3e-42)
    assert check_units([good, good], ("N",)) == []
    (msg,) = check_units([good, bad], ("N",))
    assert "u7 (p = 3e-42)" in msg and "does not describe" in msg


def test_at_population_takes_each_units_covariance_at_the_population_median():
    """The second pool's covariances (fogbayes.pool.allan.at_population): at the unit's own
    estimate they are its fit's; at a lower B, B dominates fewer taus and its log-space
    variance grows (the direction that removes the weights' lean towards high estimates);
    a unit without its data is left as it is."""
    from fogbayes.allan.data import prepare
    from fogbayes.allan.fit import fit_range
    from fogbayes.pool.allan import at_population, unit_from_fit
    from fogbayes.simulate.noise import allan_noise

    # a unit of benchmarks/bench_pool.py's fleets (a tactical FOG at 10 Hz), 55 min; the
    # flicker drawn over 4x the record, as there
    n, fs = 2 ** 15, 10.0
    y = allan_noise(4 * n, fs, seed=7, flicker_span=1, Q=0.19, N=0.01, B=0.165, K=0.66)[:n]
    unit = unit_from_fit("u0", None, n, fs, *fit_range(prepare(y, fs)))
    own = {t: unit.terms[t].value for t in ("N", "B")}
    (same,) = at_population([unit], ("N", "B"), own)
    np.testing.assert_allclose(same.cov, unit.cov, rtol=1e-9, atol=1e-14)
    (low,) = at_population([unit], ("B",), {"B": own["B"] / 2})
    b = TERMS.index("B")
    assert low.cov[b, b] > 1.2 * unit.cov[b, b]
    assert np.array_equal(low.logp, unit.logp)  # the estimate itself does not move
    bare = unit._replace(data=None, fit=None)
    assert at_population([bare], ("B",), {"B": own["B"] / 2})[0] is bare
