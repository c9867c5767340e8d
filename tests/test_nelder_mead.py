"""support.nelder_mead takes SciPy's Nelder-Mead steps: same point, value and evaluations."""

import numpy as np
import pytest
from scipy.optimize import minimize, rosen

from fogbayes.support.nelder_mead import nelder_mead


def _scipy(fun, simplex, **tol):
    return minimize(fun, simplex[0], method="Nelder-Mead",
                    options={"initial_simplex": simplex, **tol})


def _quartic_valley(x):  # ties and plateaus: flat in x[2] beyond |x[2]| > 1
    return float((x[0] - 1) ** 4 + 3 * (x[1] + 0.5) ** 2 + np.clip(x[2], -1, 1) ** 2)


@pytest.mark.parametrize("fun,dim", [(rosen, 2), (rosen, 4), (_quartic_valley, 3)])
@pytest.mark.parametrize("seed", range(4))
def test_same_steps_as_scipy(fun, dim, seed):
    rng = np.random.default_rng(seed)
    simplex = rng.normal(scale=2.0, size=(dim + 1, dim))
    tol = {"xatol": 1e-3, "fatol": 1e-5, "maxiter": 300}
    ours, ref = nelder_mead(fun, simplex, **tol), _scipy(fun, simplex, **tol)
    np.testing.assert_array_equal(ours.x, ref.x)
    assert ours.fun == ref.fun and ours.nfev == ref.nfev and ours.nit == ref.nit
    assert ours.success == ref.success


def test_reports_running_out_of_iterations():
    simplex = np.array([[-1.2, 1.0], [-1.0, 1.0], [-1.2, 1.2]])
    ours = nelder_mead(rosen, simplex, xatol=1e-12, fatol=1e-12, maxiter=20)
    ref = _scipy(rosen, simplex, xatol=1e-12, fatol=1e-12, maxiter=20)
    assert not ours.success and not ref.success
    np.testing.assert_array_equal(ours.x, ref.x)


def test_the_composite_reml_fit_is_unchanged(monkeypatch):
    """The REML noise fit gives SciPy's answer bit for bit on a cell table."""
    from fogbayes.composite import noise

    rng = np.random.default_rng(3)
    K, per = 40, 30
    cell = np.repeat(np.arange(K), per)
    X = np.column_stack([np.ones(K * per), rng.normal(size=K * per)])
    walk = np.cumsum(rng.normal(scale=0.3, size=K))
    y = X @ [0.5, 2.0] + walk[cell] + rng.normal(size=K * per)
    st = noise.cell_stats(X, y, cell, np.arange(K * per, dtype=float))
    ours = noise.fit_cell_noise(st)

    def scipy_nm(fun, simplex, *, xatol, fatol, maxiter):
        return _scipy(fun, simplex, xatol=xatol, fatol=fatol, maxiter=maxiter)

    monkeypatch.setattr(noise, "nelder_mead", scipy_nm)
    ref = noise.fit_cell_noise(st)
    assert ours.lam > 1e-6  # the walk is found, so the simplex did work
    assert (ours.lam, ours.rho, ours.reml) == (ref.lam, ref.rho, ref.reml)
    np.testing.assert_array_equal(ours.theta, ref.theta)
