"""The L-BFGS-B driver and the many-problem noise fit.

References: SciPy's own ``scipy.optimize.minimize`` with the same options for the driver; one
``fit_noise`` per problem for ``fit_noise_many`` (optima compared to 1e-8 in log-likelihood:
far below the 0.5-unit differences the evidence rules act on).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import optimize

from fogbayes.inference.lbfgsb import failed_as_large, minimize_one_by_one


def _rosenbrock_batch(shifts):
    """Shifted Rosenbrock functions, problem i shifted by shifts[i]; the last problem is NaN
    (a failed point) wherever x0 < 0."""
    calls = []

    def batch(rows, xs):
        calls.append(rows.copy())
        x = xs - shifts[rows]
        a, b = x[:, 0], x[:, 1]
        f = (1 - a) ** 2 + 100 * (b - a * a) ** 2
        g = np.column_stack([-2 * (1 - a) - 400 * a * (b - a * a), 200 * (b - a * a)])
        bad = (rows == len(shifts) - 1) & (xs[:, 0] < 0.0)
        return np.where(bad, np.nan, f), np.where(bad[:, None], np.nan, g)

    return batch, calls


def test_runs_equal_scipys_own_minimize():
    rng = np.random.default_rng(0)
    shifts = 0.5 * np.abs(rng.normal(size=(7, 2)))  # minima (1, 1) + shift: inside the box
    starts = [np.array([-1.2, 1.0]) + rng.normal(scale=0.3, size=2) for _ in range(7)]
    bounds = [(-1.6, 3.0), (-2.0, 4.0)]
    batch, calls = _rosenbrock_batch(shifts)
    runs = minimize_one_by_one(batch, starts, bounds)
    assert max(len(c) for c in calls) == 1 and len(calls) == sum(r.nfev for r in runs)
    for r, s in zip(runs[:-1], shifts):
        np.testing.assert_allclose(r.x, s + 1.0, atol=1e-4)  # the shifted minimum (1, 1)
    for i in (0, 6):  # the same as SciPy's own minimize on the scalar function
        one = _rosenbrock_batch(shifts)[0]
        f = lambda x, i=i: tuple(v[0] for v in one(np.array([i]), x[None]))  # noqa: E731
        ref = optimize.minimize(f, starts[i], jac=True, method="L-BFGS-B", bounds=bounds)
        if i == 6:  # NaN where x0 < 0: the driver sees a failed point, not a NaN
            ref = optimize.minimize(lambda x: failed_as_large(*f(x)), starts[i], jac=True,
                                    method="L-BFGS-B", bounds=bounds)
        np.testing.assert_array_equal(runs[i].x, ref.x)
        assert runs[i].nfev == ref.nfev


def test_fit_noise_many_equals_one_fit_per_problem():
    from fogbayes.inference import noise_ssm as ns
    from fogbayes.inference.noise_fit import fit_noise, fit_noise_many
    from fogbayes.loop.nullsim import simulate

    spec = ns.make_spec(10.0, 6000.0, n_markov=1)
    n = 600
    rng = np.random.default_rng(3)
    theta = np.array([-1.0, -9.0, 0.0, np.log(300.0)])
    noise = simulate(spec, theta, 1.0, np.ones(n), 4, seed=1)
    t = np.linspace(-1, 1, n)
    X0 = np.column_stack([np.ones(n), t])
    X1 = np.column_stack([np.ones(n), t, t ** 2, np.sin(3 * t)])
    X2 = np.column_stack([np.ones(n)] + [t ** k for k in range(1, 10)])  # 10 columns: pads to 16
    mask = (rng.random(n) > 0.05).astype(float)
    ys = [0.3 + noise[:, k] for k in range(4)]
    Xs = [X0, X1, X2, X0]
    many = fit_noise_many(spec, ys, Xs, mask, np.ones(n),
                          extra_starts=[None, theta[None], None, theta[None]])
    for y, X, e, got in zip(ys, Xs, [None, theta[None], None, theta[None]], many):
        ref = fit_noise(spec, y, X, mask, np.ones(n), extra_starts=e)
        assert got.n_params == X.shape[1] and got.converged
        assert got.loglik == pytest.approx(ref.loglik, rel=1e-8, abs=1e-8)
        # theta to 1e-3 only: a negligible walk (log ratio -22) sits on a flat likelihood,
        # where rounding moves the optimum along it (measured 3e-5) without changing logL
        np.testing.assert_allclose(got.theta, ref.theta, atol=1e-3)
        np.testing.assert_allclose(got.beta, ref.beta, rtol=1e-6, atol=1e-9)


def test_starts_in_threads_give_the_lone_runs_bits(monkeypatch):
    """The starts run side by side in threads (the CPU filter releases the GIL): every
    result equals the one the same start gives alone, to the bit."""
    from fogbayes.inference import noise_ssm as ns
    from fogbayes.inference.noise_fit import fit_noise_many
    from fogbayes.loop.nullsim import simulate
    from fogbayes.support import threads

    spec = ns.make_spec(10.0, 6000.0, n_markov=1)
    n = 500
    theta = np.array([-1.0, -9.0, 0.0, np.log(300.0)])
    noise = simulate(spec, theta, 1.0, np.ones(n), 3, seed=4)
    t = np.linspace(-1, 1, n)
    X = np.column_stack([np.ones(n), t, t ** 2])
    ys = [0.2 * t + noise[:, k] for k in range(3)]

    def fits(workers):
        monkeypatch.setattr(threads, "WORKERS", workers)
        return fit_noise_many(spec, ys, [X] * 3, n_starts=3)

    threaded, alone = fits(2), fits(1)
    for a, b in zip(threaded, alone):
        np.testing.assert_array_equal(a.theta, b.theta)
        np.testing.assert_array_equal(a.beta, b.beta)
        assert a.loglik == b.loglik and a.converged == b.converged


@pytest.mark.parametrize("value,expected", [("1", 1), ("64", None), ("0", None), ("x", None)])
def test_fogbayes_threads_caps_the_thread_count(monkeypatch, value, expected):
    """FOGBAYES_THREADS caps the threads at a positive count; 0 or a non-number leaves the
    cores' count (a thread count only changes speed, never a result)."""
    from fogbayes.support import threads

    monkeypatch.setenv("FOGBAYES_THREADS", value)
    monkeypatch.delattr(threads.os, "sched_getaffinity", raising=False)
    monkeypatch.setattr(threads.os, "cpu_count", lambda: 8)
    assert threads._workers() == (8 if expected is None else expected)
