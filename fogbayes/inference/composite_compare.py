"""Order selection for the composite model: paper 000's sigma_d, and WAIC / LOO.

``criterion="sigma_d"`` is the paper's rule (eq. 11, :mod:`.composite_classify`): the order
with the smallest RMS fit error. It is known to over-fit (a useless extra coefficient
lowers sigma_d about half the time); measured recovery is in benchmarks/RESULTS_composite.md.

``criterion="loo"`` / ``"waic"``: each candidate is fitted by GLS with the cell-offset
noise model (:mod:`.composite_noise`), whose variance parameters (lam, rho) are estimated
once by REML at the largest orders searched and then held fixed, so every candidate is
judged under the same noise. Its posterior (flat prior, s^2 profiled) is the Gaussian
N(theta_hat, cov); draws give the pointwise log-likelihood per *cell* (cells, not
correlated samples, are the units left out), from which ArviZ computes elpd_loo (PSIS)
or elpd_waic. Orders are searched one coordinate at a time (s1, s2, u0, u1, repeated
until nothing changes), and along a coordinate the *smallest* order whose elpd is within
``threshold`` standard errors of the best one is kept (the standard error of the
pointwise elpd difference, as in ``az.compare``): extra terms must earn their place.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..composite_cells import RateData
from ..models.composite import Orders, Scaling, design_matrix
from .composite_fit import default_scaling
from .composite_noise import _solve, cell_stats, fit_cell_noise

CRITERIA = ("loo", "waic", "sigma_d")


class OrderScore(NamedTuple):
    orders: Orders
    elpd: float
    se: float
    pointwise: np.ndarray  # (K,)


class OrderSelection(NamedTuple):
    orders: Orders
    criterion: str
    scores: dict  # label -> (elpd, se) of every candidate evaluated
    lam: float
    rho: float


def _cell_pointwise(X, y, cell, lam, theta_draws, s2):
    """(S, K) log-likelihood per cell: within-cell part + the cell mean's marginal density."""
    K = int(cell.max()) + 1
    N = np.bincount(cell, minlength=K).astype(float)
    Xb = np.stack([np.bincount(cell, X[:, j], K) for j in range(X.shape[1])], axis=1) / N[:, None]
    yb = np.bincount(cell, y, K) / N
    Xc, yc = X - Xb[cell], y - yb[cell]
    # within-cell residual sum of squares for every draw: sum over samples of (yc - Xc th)^2
    R = yc[None, :] - theta_draws @ Xc.T  # (S, n)
    within = np.stack([np.bincount(cell, r * r, K) for r in R])
    rb = yb[None, :] - theta_draws @ Xb.T
    v = s2 * (1.0 / N + lam)
    ll = (-0.5 * ((N - 1) * np.log(2 * np.pi * s2) + within / s2)
          - 0.5 * (np.log(2 * np.pi * v) + rb * rb / v) - 0.5 * np.log(N))
    return ll


def score_orders(data: RateData, orders: Orders, sc: Scaling, lam: float, rho: float, *,
                 criterion: str = "loo", draws: int = 400, seed: int = 0) -> OrderScore:
    """elpd (LOO or WAIC over cells) of one candidate under fixed noise (lam, rho)."""
    import arviz as az

    X = np.asarray(design_matrix(orders, sc, data.T, data.W, data.t))
    y = (data.U - sc.U_ref) / sc.U_scale
    st = cell_stats(X, y, data.cell, data.time)
    theta, G, rss, _, dof = _solve(st, lam, rho)
    s2 = rss / dof
    cov = s2 * np.linalg.inv(G)
    rng = np.random.default_rng(seed)
    th = rng.multivariate_normal(theta, cov, size=draws, method="cholesky")
    ll = _cell_pointwise(X, y, data.cell, lam, th, s2)
    idata = az.from_dict(posterior={"theta": th[None]}, log_likelihood={"cells": ll[None]})
    if criterion == "waic":
        res = az.waic(idata, pointwise=True)
        return OrderScore(orders, float(res.elpd_waic), float(res.se),
                          np.asarray(res.waic_i).ravel())
    res = az.loo(idata, pointwise=True)
    return OrderScore(orders, float(res.elpd_loo), float(res.se), np.asarray(res.loo_i).ravel())


def select_orders(data: RateData, *, criterion: str = "loo", scaling: Scaling | None = None,
                  start: Orders = Orders(2, 2, 2, 2), max_order: int = 4,
                  threshold: float = 2.0, seed: int = 0) -> OrderSelection:
    """Coordinate-wise order search by LOO or WAIC over cells (module doc)."""
    from .composite_classify import classify_fit

    sc = scaling or default_scaling(data)
    if criterion == "sigma_d":
        cf = classify_fit(data, scaling=sc)
        return OrderSelection(cf.orders, criterion, {"sigma_u1": cf.sigma_u1,
                              "sigma_s1": cf.sigma_s1, "sigma_s2": cf.sigma_s2}, 0.0, 0.0)
    top = Orders(max_order, max_order, max_order, max_order)
    X = np.asarray(design_matrix(top, sc, data.T, data.W, data.t))
    y = (data.U - sc.U_ref) / sc.U_scale
    noise = fit_cell_noise(cell_stats(X, y, data.cell, data.time))
    cache: dict = {}

    def score(o: Orders) -> OrderScore:
        if o not in cache:
            cache[o] = score_orders(data, o, sc, noise.lam, noise.rho,
                                    criterion=criterion, seed=seed)
        return cache[o]

    cur = start
    for _ in range(4):
        before = cur
        for k in range(4):
            cands = [cur._replace(**{cur._fields[k]: d}) for d in range(max_order + 1)]
            sc_ = [score(o) for o in cands]
            best = max(sc_, key=lambda s: s.elpd)
            for s in sc_:  # smallest order within `threshold` SE of the best
                diff = best.pointwise - s.pointwise
                se = float(np.sqrt(diff.size * np.var(diff)))
                if best.elpd - s.elpd <= threshold * se:
                    cur = s.orders
                    break
        if cur == before:
            break
    scores = {o.label(): (s.elpd, s.se) for o, s in cache.items()}
    return OrderSelection(cur, criterion, scores, noise.lam, noise.rho)
