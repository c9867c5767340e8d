"""Bounded L-BFGS-B minimisations (SciPy's), the one driver of the package's smooth fits.

The objective is ``batch(rows, points) -> (values (b,), grads (b, d))`` (``rows[i]``: which
minimisation), called here one row at a time; a non-finite value or gradient is a failed point.
The starts run side by side in threads (:func:`fogbayes.support.threads.thread_map`):
SciPy's L-BFGS-B keeps its state in each call's own arrays, and the objectives here spend most
of their time in the CPU filter, which releases the GIL, so each result is a lone run's.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
from scipy import optimize

from ..support import threads

Batch = Callable[[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]]


def failed_as_large(v, g) -> tuple[float, np.ndarray]:
    """A non-finite value or gradient goes to L-BFGS-B as (1e300, 0): a failed point."""
    v, g = float(v), np.array(g, dtype=float)
    if np.isfinite(v) and bool(np.all(np.isfinite(g))):
        return v, g
    return 1e300, np.zeros_like(g)


def minimize_one_by_one(batch: Batch, starts: Sequence[np.ndarray], bounds, *,
                        maxiter: int = 200) -> list[optimize.OptimizeResult]:
    """L-BFGS-B from each start (the same bounds), the starts side by side in threads
    (module doc); ``batch`` is called with one row per evaluation (from those threads: it must not
    share mutable state between rows). Returns the SciPy results in the order of ``starts``."""
    def run(i: int):
        row = np.array([i])

        def fun(x):
            v, g = batch(row, np.asarray(x, dtype=float)[None])
            return failed_as_large(v[0], g[0])

        return optimize.minimize(fun, np.asarray(starts[i], float), jac=True,
                                 method="L-BFGS-B", bounds=bounds, options={"maxiter": maxiter})

    return threads.thread_map(run, range(len(starts)))
