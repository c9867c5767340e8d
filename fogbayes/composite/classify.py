"""Paper 000's "classification fitting" (section 3), with uncertainties.

Per cell U_ij = A_ij + B_ij t (eq. 10); U1(T_i) = mean_j B_ij fitted with orders 1..4 chosen by
sigma_d = sqrt(sum (k - k^)^2 / (n - d - 1)) (eq. 11), U0 the same order; S1 and S2 orders
from A_ij over T and over W (pooled sigma_d); M and c from A_ij (eqs. 15/16) by GLS with the
cell-offset noise (:mod:`fogbayes.composite.noise`), d by OLS with Student-t intervals (eq. 12).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .cells import CellSummary, RateData, summarise_cells
from ..errors import TooShortError
from .model import FullParams, Orders, Scaling, design_matrix
from .fit import default_scaling
from .noise import cell_stats, fit_cell_noise


class ClassificationFit(NamedTuple):
    """Result of :func:`classify_fit` (scaled parameters; grids are n_T x n_W, NaN = no cell)."""

    A: np.ndarray
    B: np.ndarray
    U1_levels: np.ndarray  # (n_T,) mean_j B_ij
    sigma_u1: dict  # order -> sigma_d of the U1(T) fit
    sigma_s1: dict  # order -> pooled sigma_d of A over T
    sigma_s2: dict  # polynomial order in W (2..5) -> pooled sigma_d of A over W
    orders: Orders
    params: FullParams
    scaling: Scaling
    cov: np.ndarray  # (p, p) of pack(params); block diagonal between (M, c) and d
    dof: int  # smallest residual dof of the two stages (for Student-t intervals)


def sigma_d(x: np.ndarray, k: np.ndarray, d: int) -> tuple[float, int]:
    """Eq. 11 for one polynomial fit of order d: returns (SSE, n - d - 1)."""
    x, k = np.asarray(x, float), np.asarray(k, float)
    ok = np.isfinite(k)
    x, k = x[ok], k[ok]
    if k.size <= d + 1:
        return np.nan, 0
    coef = np.polynomial.polynomial.polyfit(x, k, d)
    r = k - np.polynomial.polynomial.polyval(x, coef)
    return float(r @ r), k.size - d - 1


def pooled_sigma_d(x: np.ndarray, K: np.ndarray, d: int) -> float:
    """sqrt(sum_g SSE_g / sum_g (n_g - d - 1)) over the rows g of K (each fitted vs x)."""
    parts = [sigma_d(x, row, d) for row in np.atleast_2d(K)]
    sse = sum(s for s, n in parts if n > 0)
    dof = sum(n for _, n in parts)
    return float(np.sqrt(sse / dof)) if dof > 0 else np.nan


def choose(table: dict) -> int:
    """The order with the smallest finite sigma_d (the paper's rule)."""
    finite = {d: s for d, s in table.items() if np.isfinite(s)}
    if not finite:
        raise TooShortError("no polynomial order can be fitted: too few temperatures or rates",
                            column="input_rate", fix="record more temperatures and rates")
    return min(finite, key=finite.get)


def cell_grid(summary: CellSummary, data: RateData) -> tuple[np.ndarray, np.ndarray]:
    """A_ij and B_ij on the (n_T, n_W) grid (mean over repeated visits of a cell)."""
    nT, nW = data.temperature_levels.size, data.rate_levels.size
    cnt = np.zeros((nT, nW))
    A, B = np.zeros((nT, nW)), np.zeros((nT, nW))
    np.add.at(cnt, (data.cell_i, data.cell_j), 1.0)
    np.add.at(A, (data.cell_i, data.cell_j), summary.intercept)
    np.add.at(B, (data.cell_i, data.cell_j), summary.slope)
    with np.errstate(invalid="ignore"):
        return np.where(cnt > 0, A / cnt, np.nan), np.where(cnt > 0, B / cnt, np.nan)


def classify_fit(data: RateData, *, orders: Orders | None = None,
                 scaling: Scaling | None = None,
                 t_orders=(1, 2, 3, 4), w_orders=(2, 3, 4, 5)) -> ClassificationFit:
    """Paper 000's identification (module doc). ``orders`` given: only step 5 is run."""
    sc = scaling or default_scaling(data)
    summ = summarise_cells(data)
    A, B = cell_grid(summ, data)
    Tl = (data.temperature_levels - sc.T_ref) / sc.T_scale
    Wl = data.rate_levels / sc.W_scale
    with np.errstate(invalid="ignore"):
        U1 = np.nanmean(B, axis=1)
    s_u1 = {d: float(np.sqrt(sse / n)) if n > 0 else np.nan
            for d in t_orders for sse, n in [sigma_d(Tl, U1, d)]}
    s_s1 = {d: pooled_sigma_d(Tl, A.T, d) for d in t_orders}
    s_s2 = {d: pooled_sigma_d(Wl, A, d) for d in w_orders}
    if orders is None:
        u = choose(s_u1)
        orders = Orders(choose(s_s1), choose(s_s2) - 1, u, u)
    # step 5a: M and c from the A_ij (cells as observations), GLS with cell offsets
    Tc, Wc = summ.T, summ.W
    Xa = np.asarray(design_matrix(orders, sc, Tc, Wc, np.zeros_like(Tc)))
    na = Xa.shape[1] - (orders.u1 + 1)
    Xa = Xa[:, :na]
    ya = (summ.intercept - sc.U_ref) / sc.U_scale
    if ya.size <= na + 2:
        raise TooShortError(f"{ya.size} cells for {na} coefficients", column="orders",
                            fix="record more cells or lower the orders")
    tc = np.bincount(data.cell, data.time, ya.size) / summ.n  # cell mid-times: their order
    fa = fit_cell_noise(cell_stats(Xa, ya, np.arange(ya.size), tc))
    # step 5b: d from U1(T_i); U1 in scaled units is U1 * t_scale / U_scale
    ok = np.isfinite(U1)
    Xd = np.stack([Tl[ok] ** i for i in range(orders.u1 + 1)], axis=1)
    yd = U1[ok] * sc.t_scale / sc.U_scale
    dof_d = int(ok.sum()) - orders.u1 - 1
    if dof_d < 1:
        raise TooShortError(f"{int(ok.sum())} temperature levels for a U1 of order {orders.u1}",
                            column="temperature", fix="record more temperatures or lower u1")
    dd, *_ = np.linalg.lstsq(Xd, yd, rcond=None)
    rd = yd - Xd @ dd
    cov_d = float(rd @ rd) / dof_d * np.linalg.inv(Xd.T @ Xd)
    nm = (orders.s1 + 1) * (orders.s2 + 1)
    params = FullParams(fa.theta[:nm].reshape(orders.s1 + 1, orders.s2 + 1), fa.theta[nm:],
                        np.asarray(dd))
    cov = np.zeros((na + dd.size, na + dd.size))
    cov[:na, :na], cov[na:, na:] = fa.cov, cov_d
    return ClassificationFit(A, B, U1, s_u1, s_s1, s_s2, orders, params, sc, cov,
                             min(fa.dof, dof_d))
