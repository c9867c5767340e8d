"""Order selection for the composite model: paper 000's sigma_d, and WAIC / LOO.

``"sigma_d"``: eq. 11 (:mod:`.classify`; over-fits, benchmarks/RESULTS_composite.md).
``"loo"`` / ``"waic"``: GLS with the cell-offset noise (:mod:`.noise`), draws from
N(theta_hat, cov), pointwise log-likelihood per cell conditional on the other cells, ArviZ
elpd; coordinate search over (s1, s2, u0, u1) keeping the smallest order within
``threshold`` nats of the best.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .cells import RateData
from .model import Orders, Scaling, design_matrix
from .fit import default_scaling
from .noise import cell_stats, fit_cell_noise

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


def _cell_pointwise(X, y, cell, t_abs, lam, rho, theta_draws, s2):
    """(S, K) log-likelihood per cell, the cell's mean *conditional on the other cells*.

    Within-cell contrasts factorise per cell. The cell means are jointly
    N(Xb theta, s2 Sigma), Sigma = N^-1 + lam R (correlated: neighbouring cells share
    bias-instability offsets), so each cell's mean enters through
    log p(yb_k | yb_-k, theta) = -1/2 log(2 pi / Q_kk) - (Q r)_k^2 / (2 Q_kk), Q = Sigma^-1 / s2
    (exact LOO for non-factorised Gaussian models, Buerkner, Gabry & Vehtari 2021).
    """
    K = int(cell.max()) + 1
    N = np.bincount(cell, minlength=K).astype(float)
    Xb = np.stack([np.bincount(cell, X[:, j], K) for j in range(X.shape[1])], axis=1) / N[:, None]
    yb = np.bincount(cell, y, K) / N
    # samples sorted by cell (every cell holds samples: rate_data's cells are plateaus), so
    # each draw's within-cell sums of squares are one reduceat over the (S, n) residuals
    order = np.argsort(cell, kind="stable")
    starts = np.searchsorted(cell[order], np.arange(K))
    Xc, yc = (X - Xb[cell])[order], (y - yb[cell])[order]
    R = yc[None, :] - theta_draws @ Xc.T  # (S, n) within-cell residuals
    within = np.add.reduceat(R * R, starts, axis=1)
    tau = np.bincount(cell, t_abs, K) / N
    d = np.diff(np.sort(tau))
    spacing = float(np.median(d)) if d.size and np.median(d) > 0 else 1.0
    Rc = rho ** (np.abs(tau[:, None] - tau[None, :]) / spacing) if rho > 0 else np.eye(K)
    Q = np.linalg.inv(np.diag(1.0 / N) + lam * Rc) / s2
    rb = yb[None, :] - theta_draws @ Xb.T  # (S, K)
    g = rb @ Q  # Q symmetric
    q = np.diag(Q)
    mean_part = -0.5 * np.log(2 * np.pi / q) - 0.5 * g * g / q
    return (-0.5 * ((N - 1) * np.log(2 * np.pi * s2) + within / s2) - 0.5 * np.log(N)
            + mean_part)


def score_orders(data: RateData, orders: Orders, sc: Scaling, *, criterion: str = "loo",
                 draws: int = 400, seed: int = 0) -> OrderScore:
    """elpd (LOO or WAIC over cells) of one candidate; its noise (lam, rho) by REML."""
    from ..inference.compare import information

    X = np.asarray(design_matrix(orders, sc, data.T, data.W, data.t))
    y = (data.U - sc.U_ref) / sc.U_scale
    fit = fit_cell_noise(cell_stats(X, y, data.cell, data.time))
    rng = np.random.default_rng(seed)
    th = rng.multivariate_normal(fit.theta, fit.cov, size=draws, method="cholesky")
    ll = _cell_pointwise(X, y, data.cell, data.time, fit.lam, fit.rho, th, fit.s2)
    res = information(np.asarray(ll, float), "waic" if criterion == "waic" else "loo")
    return OrderScore(orders, res.elpd, res.se, res.pointwise)


def select_orders(data: RateData, *, criterion: str = "loo", scaling: Scaling | None = None,
                  start: Orders = Orders(2, 2, 2, 2), max_order: int = 4,
                  threshold: float = 4.0, seed: int = 0) -> OrderSelection:
    """Coordinate-wise order search by LOO or WAIC over cells (module doc)."""
    from .classify import classify_fit

    sc = scaling or default_scaling(data)
    if criterion == "sigma_d":
        cf = classify_fit(data, scaling=sc)
        return OrderSelection(cf.orders, criterion, {"sigma_u1": cf.sigma_u1,
                              "sigma_s1": cf.sigma_s1, "sigma_s2": cf.sigma_s2})
    cache: dict = {}

    def score(o: Orders) -> OrderScore:
        if o not in cache:
            cache[o] = score_orders(data, o, sc, criterion=criterion, seed=seed)
        return cache[o]

    cur = start
    for _ in range(4):
        before = cur
        for k in range(4):
            cands = [cur._replace(**{cur._fields[k]: d}) for d in range(max_order + 1)]
            sc_ = [score(o) for o in cands]
            best = max(sc_, key=lambda s: s.elpd)
            for s in sc_:  # smallest order within `threshold` nats of the best
                if best.elpd - s.elpd <= threshold:
                    cur = s.orders
                    break
        if cur == before:
            break
    scores = {o.label(): (s.elpd, s.se) for o, s in cache.items()}
    return OrderSelection(cur, criterion, scores)
