"""Bounded L-BFGS-B minimisations (SciPy's), the one driver of the package's smooth fits.

The objective is ``batch(rows, points) -> (values (b,), grads (b, d))`` (``rows[i]``: which
minimisation), called here one row at a time; a non-finite value or gradient is a failed point.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
from scipy import optimize

Batch = Callable[[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]]


def failed_as_large(v, g) -> tuple[float, np.ndarray]:
    """A non-finite value or gradient goes to L-BFGS-B as (1e300, 0): a failed point."""
    v, g = float(v), np.array(g, dtype=float)
    if np.isfinite(v) and bool(np.all(np.isfinite(g))):
        return v, g
    return 1e300, np.zeros_like(g)


def minimize_one_by_one(batch: Batch, starts: Sequence[np.ndarray], bounds, *,
                        maxiter: int = 200) -> list[optimize.OptimizeResult]:
    """L-BFGS-B from each start (the same bounds), one after another; ``batch`` is called
    with one row per evaluation. Returns the SciPy results in the order of ``starts``."""
    out = []
    for i, x0 in enumerate(starts):
        row = np.array([i])

        def fun(x, row=row):
            v, g = batch(row, np.asarray(x, dtype=float)[None])
            return failed_as_large(v[0], g[0])

        out.append(optimize.minimize(fun, np.asarray(x0, float), jac=True, method="L-BFGS-B",
                                     bounds=bounds, options={"maxiter": maxiter}))
    return out
