"""ARMA order selection by AIC / BIC over a candidate set, all candidates in one compiled call.

AIC = -2 log L + 2k, BIC = -2 log L + k log n, k = p + q + 1 (zero-mean). Candidates share the
largest (P, Q) shapes with masks (:func:`fogbayes.arma.fit.fit_arma`,
:func:`~fogbayes.models.buckets.bucket_length`). Default ``criterion="bic"`` (consistent).
"""

from __future__ import annotations

from functools import partial
from typing import NamedTuple

import jax
import numpy as np

from ..models.buckets import held
from ..support.programs import program
from .fit import ArmaFit, default_ar_order, fit_padded

Array = jax.Array

#: Paper 002's candidate set (p, q).
PAPER_CANDIDATES: tuple[tuple[int, int], ...] = ((1, 0), (2, 0), (3, 0), (1, 1), (2, 1))


def grid_candidates(max_p: int = 3, max_q: int = 3, *, include_white: bool = True
                    ) -> tuple[tuple[int, int], ...]:
    """All (p, q) with p <= max_p, q <= max_q (white noise (0, 0) optional)."""
    return tuple((p, q) for p in range(max_p + 1) for q in range(max_q + 1)
                 if include_white or p + q > 0)


def order_name(p: int, q: int) -> str:
    """'AR(2)', 'MA(1)', 'ARMA(2,1)', 'white'."""
    if q == 0:
        return f"AR({p})" if p else "white"
    return f"ARMA({p},{q})" if p else f"MA({q})"


class OrderSelection(NamedTuple):
    """Candidates' fits and criteria (leading axis of the arrays: candidates; a batch of
    series adds an axis in front). ``fits`` holds coefficients padded to (P,) and (Q,)."""

    orders: tuple[tuple[int, int], ...]
    fits: ArmaFit
    aic: np.ndarray
    bic: np.ndarray
    n: int

    def best(self, criterion: str = "bic") -> np.ndarray:
        """Index (per series) of the candidate with the smallest criterion."""
        if criterion not in ("aic", "bic"):
            raise ValueError(f"criterion must be 'aic' or 'bic', got {criterion!r}")
        return np.argmin(self.aic if criterion == "aic" else self.bic, axis=-1)

    def selected(self, criterion: str = "bic") -> tuple[int, int]:
        """(p, q) chosen for a single series."""
        return self.orders[int(self.best(criterion))]

    def coefficients(self, index: int) -> tuple[np.ndarray, np.ndarray, float]:
        """(phi, theta, sigma2) of candidate ``index`` of a single series, unpadded."""
        p, q = self.orders[index]
        f = self.fits
        return (np.asarray(f.phi[index, :p]), np.asarray(f.theta[index, :q]),
                float(f.sigma2[index]))


def _masks(orders, P: int, Q: int) -> tuple[np.ndarray, np.ndarray]:
    # len(orders) rows even when P or Q is 0 (reshape(-1, 0) cannot infer the row count)
    mp = np.array([[1.0 if i < p else 0.0 for i in range(P)] for p, _ in orders]).reshape(len(orders), P)
    mq = np.array([[1.0 if j < q else 0.0 for j in range(Q)] for _, q in orders]).reshape(len(orders), Q)
    return mp, mq


@partial(program, static_argnames=("P", "Q", "batched"))
def _fit_one_order(x: Array, n, m, mp: Array, mq: Array, max_iter, *, P: int, Q: int,
                   batched: bool) -> ArmaFit:
    def fit(s):
        return fit_padded(s, n, m, p=P, q=Q, mask_phi=mp, mask_theta=mq, max_iter=max_iter)

    return jax.vmap(fit)(x) if batched else fit(x)


def select_order(x, candidates=PAPER_CANDIDATES, *, max_iter: int = 200) -> OrderSelection:
    """Fit every candidate (p, q) to x (n,) or to each row of x (B, n) and compute AIC/BIC."""
    orders = tuple((int(p), int(q)) for p, q in candidates)
    if not orders:
        raise ValueError("candidates must name at least one (p, q) order")
    P, Q = max(p for p, _ in orders), max(q for _, q in orders)
    mp, mq = _masks(orders, P, Q)
    x = np.asarray(x, dtype=float)
    n = x.shape[-1]
    # held in bucket_length(n) samples: one compiled program serves nearby lengths
    m = default_ar_order(n, P, Q)
    x = held(x)[0]
    # Candidates run one after another through one compiled function (the masks are
    # arguments): vmapping them would make every candidate wait for the slowest to
    # converge (measured 4x more likelihood evaluations on the p, q <= 3 grid).
    per = [_fit_one_order(x, n, m, mp[i], mq[i], max_iter, P=P, Q=Q, batched=x.ndim > 1)
           for i in range(len(orders))]
    # the glue in NumPy: an eager JAX operation is a program to trace and compile in
    # every new process
    axis = 0 if x.ndim == 1 else 1
    fits = jax.tree_util.tree_map(lambda *a: np.stack([np.asarray(v) for v in a], axis=axis),
                                  *per)
    k = np.array([p + q + 1 for p, q in orders], dtype=float)
    aic = -2.0 * fits.loglik + 2.0 * k
    bic = -2.0 * fits.loglik + k * np.log(n)
    return OrderSelection(orders, fits, aic, bic, n)
