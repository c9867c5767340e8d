"""Model and order comparison: paper 000's RMS criterion, WAIC and PSIS-LOO.

RMS criterion (paper 000, eq. 11): for a fit with d + 1 coefficients (a polynomial of
order d) to n points, choose the order with the smallest::

    sigma_d = sqrt( sum_j (k_j - k_hat_j)^2 / (n - d - 1) )

i.e. the residual standard deviation with the degrees of freedom left. With several
covariates the denominator is ``n - n_params`` (the same thing for one polynomial).
Caveat: it treats the residuals as independent. On a simulated paper-004 run (1 s blocks,
coloured noise) every adequate order scored within 0.01 % of the others (0.48929 ...
0.48931 deg/h for T orders 2-3, rate orders 1-2), so which one wins is decided by noise;
only the inadequate orders stand out. WAIC/LOO under the AR-noise posterior weigh the
evidence with the correlation taken into account (``order_criterion="loo"`` in the thermal
workflow).

WAIC and LOO come from ArviZ 0.23 (``az.waic``, ``az.loo``; the 0.x line still has
``waic``, see docs/DESIGN.md) on the pointwise log-likelihood of
:func:`fogbayes.inference.bayes.fit_linear_bayes`; :func:`compare` ranks several fits by
expected log predictive density (higher is better).
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Mapping, Sequence
from typing import NamedTuple

import numpy as np


def rms_criterion(residual: np.ndarray, n_params: int) -> float:
    """sigma_d = sqrt(sum r^2 / (n - n_params)) (paper 000 eq. 11 with n_params = d + 1)."""
    r = np.asarray(residual, dtype=float)
    dof = r.size - int(n_params)
    return float(np.sqrt(np.sum(r * r) / dof)) if dof > 0 else float("inf")


class OrderChoice(NamedTuple):
    """Candidates in the order given, their scores and the chosen one (lowest score)."""

    orders: list
    scores: list[float]
    best: object
    criterion: str


def select_order(fit_residual: Callable[[object], tuple[np.ndarray, int]],
                 orders: Sequence, *, criterion: str = "rms") -> OrderChoice:
    """Fit every candidate order and keep the one with the smallest RMS criterion.

    ``fit_residual(order) -> (residual, n_params)``. Ties go to the lower (earlier) order.
    """
    scores = []
    for order in orders:
        resid, n_params = fit_residual(order)
        scores.append(rms_criterion(resid, n_params))
    best = orders[int(np.argmin(scores))]
    return OrderChoice(list(orders), scores, best, criterion)


def waic(idata) -> dict:
    """WAIC on the deviance-free ``log`` scale: elpd_waic, its SE and p_waic (ArviZ).

    ArviZ's warning (posterior variance of a log density > 0.4) is returned as
    ``warning`` instead of being printed.
    """
    import arviz as az

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        w = az.waic(idata, scale="log")
    return {"elpd": float(w.elpd_waic), "se": float(w.se), "p": float(w.p_waic),
            "warning": bool(w.warning)}


def loo(idata) -> dict:
    """PSIS-LOO: elpd_loo, its SE, p_loo and the worst Pareto k (ArviZ; its warning about
    large k is returned as ``warning``)."""
    import arviz as az

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        lo = az.loo(idata, scale="log", pointwise=True)
    return {"elpd": float(lo.elpd_loo), "se": float(lo.se), "p": float(lo.p_loo),
            "pareto_k_max": float(np.max(np.asarray(lo.pareto_k))), "warning": bool(lo.warning)}


def compare(idatas: Mapping[str, object], *, ic: str = "loo") -> list[dict]:
    """Rank fits by elpd (``ic`` = "loo" or "waic"), best first, with elpd differences and SE."""
    import arviz as az

    with warnings.catch_warnings():  # ArviZ 0.23 sorts with pandas' deprecated inplace=True
        warnings.filterwarnings("ignore", message=".*inplace keyword.*")
        table = az.compare(dict(idatas), ic=ic, scale="log")
    return [{"model": str(name), "rank": int(row["rank"]), "elpd": float(row[f"elpd_{ic}"]),
             "p": float(row[f"p_{ic}"]), "elpd_diff": float(row["elpd_diff"]),
             "dse": float(row["dse"]), "weight": float(row["weight"])}
            for name, row in table.iterrows()]
