"""Model and order comparison: paper 000's RMS criterion, WAIC and PSIS-LOO.

RMS criterion (paper 000 eq. 11): sigma_d = sqrt(sum (k - k_hat)^2 / (n - n_params)), smallest
wins (assumes independent residuals). WAIC and PSIS-LOO: :func:`information` of a pointwise
log-likelihood -- an array of independent draws by :mod:`fogbayes.stats.psis` (ArviZ's
arithmetic without its import), chains in an InferenceData (:func:`loglik_idata`) by ArviZ
(``az.loo``, ``az.waic``, called only here: its relative efficiency needs the chains);
:func:`difference` of two fits with its standard error, :func:`compare` ranking by elpd.
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


class IC(NamedTuple):
    """An information criterion of one fit (ArviZ, ``log`` scale: higher is better)."""

    kind: str               # "loo" (PSIS-LOO) or "waic"
    elpd: float             # sum of the pointwise values
    se: float
    p: float                # effective number of parameters
    pointwise: np.ndarray   # elpd_i per observation
    pareto_k_max: float     # worst PSIS shape estimate (NaN for WAIC)
    warning: bool           # ArviZ's warning (large k / WAIC variance > 0.4), not printed
    data: object            # the ArviZ ELPDData (what ``az.compare`` takes); None from an array


def loglik_idata(log_lik, *, name: str = "y", posterior: Mapping | None = None):
    """InferenceData of a pointwise log-likelihood, (draws, n) or (chains, draws, n).

    ArviZ wants a posterior group beside it; without one a draw index serves."""
    import arviz as az

    ll = np.asarray(log_lik, dtype=float)
    ll = ll[None] if ll.ndim == 2 else ll
    if posterior is None:
        posterior = {"draw_index": np.broadcast_to(np.arange(ll.shape[1], dtype=float),
                                                   ll.shape[:2]).copy()}
    return az.from_dict(posterior=dict(posterior), log_likelihood={name: ll})


def information(idata, kind: str = "loo", reff: float = 1.0) -> IC:
    """PSIS-LOO (``kind="loo"``) or WAIC, pointwise, of ``idata``'s log-likelihood group or
    of an array (draws, n) of draws whose relative efficiency is ``reff`` (1: independent;
    for chains, ArviZ's value: :meth:`fogbayes.inference.bayes.BayesFit.relative_efficiency`).

    The one place fogbayes calls ``az.loo`` / ``az.waic``; their warnings are returned in
    ``warning`` (and the Pareto k), never printed."""
    if isinstance(idata, np.ndarray):
        from ..stats import psis

        if kind not in ("loo", "waic"):
            raise ValueError(f"unknown information criterion {kind!r}: use 'loo' or 'waic'")
        c = psis.loo(idata, reff) if kind == "loo" else psis.waic(idata)
        k_max = float(np.max(c.pareto_k)) if kind == "loo" else float("nan")
        return IC(kind, c.elpd, c.se, c.p, c.pointwise, k_max, c.warning, None)
    import arviz as az

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        if kind == "loo":
            r = az.loo(idata, pointwise=True, scale="log")
            return IC("loo", float(r.elpd_loo), float(r.se), float(r.p_loo),
                      np.asarray(r.loo_i).ravel(), float(np.max(np.asarray(r.pareto_k))),
                      bool(r.warning), r)
        if kind == "waic":
            r = az.waic(idata, pointwise=True, scale="log")
            return IC("waic", float(r.elpd_waic), float(r.se), float(r.p_waic),
                      np.asarray(r.waic_i).ravel(), float("nan"), bool(r.warning), r)
    raise ValueError(f"unknown information criterion {kind!r}: use 'loo' or 'waic'")


def difference(a: IC, b: IC) -> tuple[float, float]:
    """elpd(a) - elpd(b) and its standard error from the pointwise differences,
    ``sqrt(n var(d_i))`` (as ``az.compare``'s dse; Vehtari, Gelman & Gabry 2017, eq. 24)."""
    if a.kind != b.kind:
        raise ValueError(f"cannot difference {a.kind} with {b.kind}")
    d = a.pointwise - b.pointwise
    return float(d.sum()), float(np.sqrt(d.size * np.var(d)))


def waic(idata) -> dict:
    """WAIC on the deviance-free ``log`` scale: elpd_waic, its SE, p_waic and ArviZ's
    warning (posterior variance of a log density > 0.4), as a document's dict (``idata``:
    as :func:`information`'s)."""
    w = information(idata, "waic")
    return {"elpd": w.elpd, "se": w.se, "p": w.p, "warning": w.warning}


def loo(idata, reff: float = 1.0) -> dict:
    """PSIS-LOO: elpd_loo, its SE, p_loo, the worst Pareto k and ArviZ's warning about
    large k, as a document's dict (``idata``, ``reff``: as :func:`information`'s)."""
    lo = information(idata, "loo", reff)
    return {"elpd": lo.elpd, "se": lo.se, "p": lo.p, "pareto_k_max": lo.pareto_k_max,
            "warning": lo.warning}


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
