"""Many bounded L-BFGS-B minimisations in lockstep, their objectives evaluated as one batch.

Each SciPy L-BFGS-B runs in its own thread and posts the point it wants; when all running ones
have posted, ``batch(rows, points) -> (values (b,), grads (b, d))`` evaluates them at once
(``rows[i]``: which minimisation). Each takes exactly the steps it would alone.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Sequence

import numpy as np
from scipy import optimize

Batch = Callable[[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]]


class _Abort(Exception):
    """Raised inside a waiting minimisation when the batch evaluation failed."""


class _Rendezvous:
    """Points posted by the running minimisations, and the values handed back."""

    def __init__(self, k: int):
        self.cond = threading.Condition()
        self.running = set(range(k))
        self.posted: dict[int, np.ndarray] = {}
        self.answers: dict[int, tuple[float, np.ndarray]] = {}
        self.aborted = False

    def ask(self, i: int, x: np.ndarray) -> tuple[float, np.ndarray]:
        with self.cond:
            if self.aborted:
                raise _Abort
            self.posted[i] = np.array(x, dtype=float)
            self.cond.notify_all()
            while i not in self.answers and not self.aborted:
                self.cond.wait()
            if self.aborted:
                raise _Abort
            return self.answers.pop(i)

    def done(self, i: int) -> None:
        with self.cond:
            self.running.discard(i)
            self.cond.notify_all()

    def next_round(self) -> dict[int, np.ndarray] | None:
        """Wait until every running minimisation has posted; None when all have finished."""
        with self.cond:
            while self.running and len(self.posted) < len(self.running):
                self.cond.wait()
            if not self.running:
                return None
            posted, self.posted = self.posted, {}
            return posted

    def answer(self, values: dict[int, tuple[float, np.ndarray]]) -> None:
        with self.cond:
            self.answers.update(values)
            self.cond.notify_all()

    def abort(self) -> None:
        with self.cond:
            self.aborted = True
            self.cond.notify_all()


def failed_as_large(v, g) -> tuple[float, np.ndarray]:
    """A non-finite value or gradient goes to L-BFGS-B as (1e300, 0): a failed point."""
    v, g = float(v), np.array(g, dtype=float)
    if np.isfinite(v) and bool(np.all(np.isfinite(g))):
        return v, g
    return 1e300, np.zeros_like(g)


def minimize_one_by_one(batch: Batch, starts: Sequence[np.ndarray], bounds, *,
                        maxiter: int = 200) -> list[optimize.OptimizeResult]:
    """The same minimisations one after another, one row per evaluation (no threads).

    For a handful of starts of one problem this is faster than lockstep: a batched program
    costs a compilation per batch size, and 1-3 rows gain little from it."""
    out = []
    for i, x0 in enumerate(starts):
        row = np.array([i])

        def fun(x, row=row):
            v, g = batch(row, np.asarray(x, dtype=float)[None])
            return failed_as_large(v[0], g[0])

        out.append(optimize.minimize(fun, np.asarray(x0, float), jac=True, method="L-BFGS-B",
                                     bounds=bounds, options={"maxiter": maxiter}))
    return out


def minimize_lockstep(batch: Batch, starts: Sequence[np.ndarray], bounds, *,
                      maxiter: int = 200) -> list[optimize.OptimizeResult]:
    """L-BFGS-B from every start (the same bounds), objectives evaluated by ``batch``.

    Returns the SciPy results in the order of ``starts``; each is the one
    :func:`minimize_one_by_one` gives (the same steps). An exception of ``batch`` stops
    every minimisation and is raised here.
    """
    k = len(starts)
    meet = _Rendezvous(k)
    results: list = [None] * k
    errors: list[BaseException] = []

    def run(i: int) -> None:
        try:
            results[i] = optimize.minimize(lambda x: meet.ask(i, x), np.asarray(starts[i], float),
                                           jac=True, method="L-BFGS-B", bounds=bounds,
                                           options={"maxiter": maxiter})
        except _Abort:
            pass
        except BaseException as e:  # noqa: BLE001 -- handed to the caller below
            errors.append(e)
            meet.abort()
        finally:
            meet.done(i)

    threads = [threading.Thread(target=run, args=(i,), daemon=True) for i in range(k)]
    for th in threads:
        th.start()
    try:
        while (posted := meet.next_round()) is not None:
            rows = np.array(sorted(posted), dtype=np.int64)  # an order threads cannot change
            vals, grads = batch(rows, np.stack([posted[i] for i in rows]))
            meet.answer({int(i): failed_as_large(vals[j], grads[j]) for j, i in enumerate(rows)})
    except BaseException:
        meet.abort()
        raise
    finally:
        for th in threads:
            th.join()
    if errors:
        raise errors[0]
    return results
