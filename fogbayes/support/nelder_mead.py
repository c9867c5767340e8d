"""Nelder-Mead simplex minimisation: SciPy's steps, without importing ``scipy.optimize``.

The same algorithm as ``scipy.optimize.minimize(fun, x0, method="Nelder-Mead",
options={"initial_simplex": ..., "xatol": ..., "fatol": ..., "maxiter": ...})`` (SciPy's
non-adaptive coefficients: reflection 1, expansion 2, contraction 1/2, shrink 1/2; no bounds),
operation for operation, so it returns the same point after the same evaluations
(tests/test_nelder_mead.py holds it to SciPy). It exists because importing
``scipy.optimize`` (with the ``scipy.linalg``, ``sparse`` and ``special`` it loads) takes
~0.3 s on the project's 2-core box, an eighth of ``fogbayes fit -m composite``, whose only
optimiser this is (benchmarks/RESULTS_interactive.md).
"""

from __future__ import annotations

from typing import Callable, NamedTuple

import numpy as np


class SimplexResult(NamedTuple):
    x: np.ndarray
    fun: float
    nfev: int
    nit: int
    success: bool  # False when ``maxiter`` ran out before the tolerances were met


def nelder_mead(fun: Callable[[np.ndarray], float], initial_simplex, *, xatol: float = 1e-4,
                fatol: float = 1e-4, maxiter: int | None = None) -> SimplexResult:
    """Minimise ``fun`` from ``initial_simplex`` ((N+1, N) vertices).

    Stops when every vertex lies within ``xatol`` of the best in every coordinate and every
    vertex's value within ``fatol`` of the best one's (SciPy's test), or after ``maxiter``
    iterations (default 200 N).
    """
    sim = np.array(initial_simplex, dtype=float)
    if sim.ndim != 2 or sim.shape[0] != sim.shape[1] + 1:
        raise ValueError("initial_simplex should be an array of shape (N+1, N)")
    N = sim.shape[1]
    maxiter = N * 200 if maxiter is None else maxiter
    nfev = 0

    def f(x):
        nonlocal nfev
        nfev += 1
        return float(fun(np.copy(x)))

    fsim = np.array([f(sim[k]) for k in range(N + 1)])
    ind = np.argsort(fsim)
    sim, fsim = np.take(sim, ind, 0), np.take(fsim, ind, 0)
    ind = np.argsort(fsim)  # SciPy sorts twice; the second is a no-op kept for identical ties
    sim, fsim = np.take(sim, ind, 0), np.take(fsim, ind, 0)

    converged = False
    iterations = 1
    while iterations < maxiter:
        if (np.max(np.ravel(np.abs(sim[1:] - sim[0]))) <= xatol
                and np.max(np.abs(fsim[0] - fsim[1:])) <= fatol):
            converged = True
            break
        xbar = np.add.reduce(sim[:-1], 0) / N
        xr = 2.0 * xbar - sim[-1]
        fxr = f(xr)
        if fxr < fsim[0]:
            xe = 3.0 * xbar - 2.0 * sim[-1]
            fxe = f(xe)
            sim[-1], fsim[-1] = (xe, fxe) if fxe < fxr else (xr, fxr)
        elif fxr < fsim[-2]:
            sim[-1], fsim[-1] = xr, fxr
        else:
            shrink = False
            if fxr < fsim[-1]:  # outside contraction
                xc = 1.5 * xbar - 0.5 * sim[-1]
                fxc = f(xc)
                if fxc <= fxr:
                    sim[-1], fsim[-1] = xc, fxc
                else:
                    shrink = True
            else:  # inside contraction
                xcc = 0.5 * xbar + 0.5 * sim[-1]
                fxcc = f(xcc)
                if fxcc < fsim[-1]:
                    sim[-1], fsim[-1] = xcc, fxcc
                else:
                    shrink = True
            if shrink:
                for j in range(1, N + 1):
                    sim[j] = sim[0] + 0.5 * (sim[j] - sim[0])
                    fsim[j] = f(sim[j])
        iterations += 1
        ind = np.argsort(fsim)
        sim, fsim = np.take(sim, ind, 0), np.take(fsim, ind, 0)
    return SimplexResult(sim[0].copy(), float(fsim[0]), nfev, iterations, converged)
