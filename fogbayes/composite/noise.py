"""Cell-offset noise for rate-table fits: white noise plus a slow offset per cell.

y = X theta + Z eta + e, e ~ N(0, s^2 I), eta ~ N(0, s^2 lam R), R_kl = rho^(|tau_k - tau_l| / dtau).
With cell means and Sigma = N^-1 + lam R: G = W_XX + Xb'Sigma^-1 Xb, h = W_Xy + Xb'Sigma^-1 yb,
theta = G^-1 h, s^2 = RSS / (n - p), cov = s^2 G^-1, with RSS = |r_w|^2 + rb'Sigma^-1 rb from the
residuals (r_w within cells, through the triangular factor of [X y]; rb = yb - Xb theta).
R^-1 = Q is tridiagonal, so Sigma^-1 v and log|Sigma| = log|R| + log|Q + lam N| - sum log n_k
cost O(K p) (LAPACK's banded Cholesky); (lam, rho) by REML; lam -> 0 is OLS.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from scipy.linalg.lapack import dpbtrf, dtbtrs

from ..support.nelder_mead import nelder_mead


class CellStats(NamedTuple):
    """Sufficient statistics of a linear model with cell offsets (cells in time order)."""

    WXX: np.ndarray  # (p, p) within-cell scatter of X
    WXy: np.ndarray  # (p,)
    Wyy: float
    Xb: np.ndarray  # (K, p) cell means of X
    yb: np.ndarray  # (K,) cell means of y
    N: np.ndarray  # (K,) samples per cell
    gaps: np.ndarray  # (K-1,) spacing of consecutive cells / their median spacing
    n: int
    R: np.ndarray  # (p+1, p+1) triangular factor of the within-cell [X y]: R'R = [[WXX WXy] [. Wyy]]


class CellNoiseFit(NamedTuple):
    theta: np.ndarray
    cov: np.ndarray
    s2: float  # white-noise variance (scaled units)
    lam: float  # cell-offset variance / s2
    rho: float  # correlation of consecutive cells
    reml: float
    dof: int


def cell_stats(X: np.ndarray, y: np.ndarray, cell: np.ndarray, t_abs: np.ndarray) -> CellStats:
    """Cell means (sorted by cell mid-time), within-cell scatter and the cell spacing."""
    K = int(cell.max()) + 1
    N = np.bincount(cell, minlength=K).astype(float)
    Xb = np.stack([np.bincount(cell, X[:, j], K) for j in range(X.shape[1])], axis=1) / N[:, None]
    yb = np.bincount(cell, y, K) / N
    Xc, yc = X - Xb[cell], y - yb[cell]
    tau = np.bincount(cell, t_abs, K) / N
    order = np.argsort(tau, kind="stable")
    d = np.diff(tau[order])
    spacing = float(np.median(d)) if d.size and np.median(d) > 0 else 1.0
    Z = np.column_stack([Xc, yc])
    R = np.linalg.qr(Z, mode="r") if Z.shape[0] >= Z.shape[1] else np.linalg.cholesky(
        Z.T @ Z + 1e-300 * np.eye(Z.shape[1])).T
    return CellStats(Xc.T @ Xc, Xc.T @ yc, float(yc @ yc), Xb[order], yb[order], N[order],
                     d / spacing, int(y.size), R)


def precision_bands(gaps: np.ndarray, rho: float):
    """Tridiagonal Q = R^-1 of an AR(1) at the cell times, and log|R|.

    With r_k = rho ** gap_k between cells k and k+1: x_1 ~ N(0, 1) and
    x_{k+1} | x_k ~ N(r_k x_k, 1 - r_k^2), so Q has diagonal 1 + r_k^2 / (1 - r_k^2)
    (from the right neighbour) + 1 / (1 - r_{k-1}^2) - 1 (from the left), off-diagonal
    -r_k / (1 - r_k^2), and log|R| = sum_k log(1 - r_k^2).
    """
    r = rho ** gaps if rho > 0 else np.zeros_like(gaps)
    w = 1.0 / (1.0 - r * r)
    diag = np.ones(gaps.size + 1)
    diag[:-1] += r * r * w
    diag[1:] += w - 1.0
    return diag, -r * w, float(np.sum(np.log1p(-r * r)))


def _between(st: CellStats, lam: float, rho: float):
    """The cell means' GLS pieces for (lam, rho): (Omega, F, small, diag, off, log|V|) with
    Omega = [Xb yb]' Sigma^-1 [Xb yb], what :func:`_quadratic` needs, and
    log|V| = log|R| + log|Q + lam N| (module doc).

    L L' = Q + lam N (LAPACK's banded Cholesky, O(K)) and Woodbury either way round, the
    better-conditioned one: for lam N small, Sigma^-1 = N - lam N (L L')^-1 N, so
    v' Sigma^-1 v = v'N v - lam |L^-1 N v|^2; for lam N large,
    Sigma^-1 = (Q - Q (L L')^-1 Q) / lam, so v' Sigma^-1 v = (v'Q v - |L^-1 Q v|^2) / lam.
    Both need one triangular solve of the p + 1 columns, F = L^-1 B[Xb yb] (B = N or Q):
    a residual rb = yb - Xb theta then has L^-1 B rb = F_y - F_x theta without a second one.
    """
    diag, off, logdetR = precision_bands(st.gaps, float(rho))
    small = bool(lam * np.median(st.N) <= 1.0)
    band = np.empty((2, diag.size))
    band[0] = diag + lam * st.N
    band[1, :-1], band[1, -1] = off, 0.0
    L, info = dpbtrf(band, lower=1)
    if info != 0:  # Q + lam N is positive definite for lam >= 0, 0 <= rho < 1, but may not
        L = np.full_like(band, np.nan)  # be to working precision: NaN, a failed simplex point
    logdetQN = 2.0 * float(np.sum(np.log(L[0])))
    Z = np.column_stack([st.Xb, st.yb])
    if small:
        B = st.N[:, None] * Z
    else:
        B = diag[:, None] * Z
        B[:-1] += off[:, None] * Z[1:]
        B[1:] += off[:, None] * Z[:-1]
    F = dtbtrs(L, B, uplo="L")[0]
    C = Z.T @ B
    Omega = C - lam * (F.T @ F) if small else (C - F.T @ F) / lam
    return Omega, F, small, diag, off, logdetR + logdetQN


def _quadratic(st: CellStats, lam: float, small: bool, diag, off, v, Fv) -> float:
    """v' Sigma^-1 v from v and L^-1 B v (see :func:`_between`)."""
    if small:
        return float(st.N @ (v * v) - lam * (Fv @ Fv))
    vQv = float(diag @ (v * v) + 2.0 * off @ (v[:-1] * v[1:]))
    return (vQv - float(Fv @ Fv)) / lam


def _solve(st: CellStats, lam: float, rho: float):
    """GLS pieces for given (lam, rho) (module doc): theta, G, RSS, REML, dof."""
    p = st.WXX.shape[0]
    Omega, F, small, diag, off, logdetV = _between(st, lam, rho)
    G = st.WXX + Omega[:p, :p]
    h = st.WXy + Omega[:p, p]
    theta = np.linalg.solve(G, h)
    # RSS from the residuals, not q - h'theta: on a rate table fitted to 1e-3 of its
    # spread, that difference loses ~9 digits and the REML surface turned noisy (5e-3 nats in
    # second differences on the paper000 table; 8e-8 from the residuals)
    within = st.R[:p, p] - st.R[:p, :p] @ theta  # within-cell residual: |.|^2 + R_yy^2
    rb = st.yb - st.Xb @ theta
    between = _quadratic(st, lam, small, diag, off, rb, F[:, p] - F[:, :p] @ theta)
    rss = max(float(within @ within + st.R[p, p] ** 2 + between), 1e-300)
    logdetG = np.linalg.slogdet(G)[1]
    dof = st.n - p
    reml = -0.5 * (dof * np.log(rss / dof) + logdetV + logdetG)  # log|V| = log|N| + log|Sigma|
    return theta, G, rss, reml, dof


def fit_cell_noise(st: CellStats, *, lam0: float = 1e-2, rho0: float = 0.5) -> CellNoiseFit:
    """REML estimate of (lam, rho), then GLS theta and its covariance s^2 G^-1.

    Nelder-Mead over (log lam, logit(rho / 0.99)); the white-noise limit (lam = e^-30,
    i.e. OLS) is kept when REML does not beat it, so clean data give back OLS.
    """
    def unpack(z):
        return float(np.exp(np.clip(z[0], -30.0, 20.0))), float(0.99 / (1 + np.exp(-z[1])))

    def nll(z):
        lam, rho = unpack(z)
        return -_solve(st, lam, rho)[3]

    z0 = np.array([np.log(lam0), np.log(rho0 / (0.99 - rho0))])
    best = nelder_mead(nll, z0 + np.array([[0, 0], [3.0, 0], [0, 2.0]]), xatol=1e-3,
                       fatol=1e-5, maxiter=300)
    white = np.array([-30.0, 0.0])
    z = best.x if best.fun < nll(white) else white
    lam, rho = unpack(z)
    theta, G, rss, reml, dof = _solve(st, lam, rho)
    s2 = rss / dof
    return CellNoiseFit(theta, s2 * np.linalg.inv(G), s2, lam, rho, reml, dof)
