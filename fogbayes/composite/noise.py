"""Cell-offset noise for rate-table fits: white noise plus a slow offset per cell.

y = X theta + Z eta + e, e ~ N(0, s^2 I), eta ~ N(0, s^2 lam R), R_kl = rho^(|tau_k - tau_l| / dtau).
With cell means and Sigma = N^-1 + lam R: G = W_XX + Xb'Sigma^-1 Xb, h = W_Xy + Xb'Sigma^-1 yb,
theta = G^-1 h, s^2 = (q - h'theta) / (n - p), cov = s^2 G^-1. R^-1 = Q is tridiagonal, so
Sigma^-1 v and log|Sigma| = log|R| + log|Q + lam N| - sum log n_k cost O(K p^2); (lam, rho) by
REML; lam -> 0 is OLS.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from scipy.optimize import minimize


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
    return CellStats(Xc.T @ Xc, Xc.T @ yc, float(yc @ yc), Xb[order], yb[order], N[order],
                     d / spacing, int(y.size))


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


def sigma_inverse(N: np.ndarray, gaps: np.ndarray, lam: float, rho: float):
    """(apply Sigma^-1 to a (K,) or (K, m) array, log|Sigma|) for Sigma = N^-1 + lam R."""
    from scipy.linalg import cho_solve_banded, cholesky_banded

    diag, off, logdetR = precision_bands(gaps, rho)
    ab = np.zeros((2, N.size))
    ab[0, 1:] = off
    ab[1] = diag + lam * N
    cb = cholesky_banded(ab)

    def Qv(v):
        out = diag.reshape((-1,) + (1,) * (v.ndim - 1)) * v
        o = off.reshape((-1,) + (1,) * (v.ndim - 1))
        out[:-1] += o * v[1:]
        out[1:] += o * v[:-1]
        return out

    def apply(v):
        Nv = N.reshape((-1,) + (1,) * (v.ndim - 1)) * v
        if lam * np.median(N) <= 1.0:
            Nb = N.reshape((-1,) + (1,) * (v.ndim - 1))
            return Nv - lam * Nb * cho_solve_banded((cb, False), Nv)
        q = Qv(v)
        return (q - Qv(cho_solve_banded((cb, False), q))) / lam

    logdet = logdetR + 2 * float(np.sum(np.log(cb[1]))) - float(np.sum(np.log(N)))
    return apply, logdet


def _solve(st: CellStats, lam: float, rho: float):
    """GLS pieces for given (lam, rho) (module doc)."""
    p = st.WXX.shape[0]
    apply, logdetS = sigma_inverse(st.N, st.gaps, lam, rho)
    SX, Sy = apply(st.Xb), apply(st.yb)
    G = st.WXX + st.Xb.T @ SX
    h = st.WXy + st.Xb.T @ Sy
    q = st.Wyy + st.yb @ Sy
    theta = np.linalg.solve(G, h)
    rss = max(float(q - h @ theta), 1e-300)
    logdetV = float(np.sum(np.log(st.N))) + logdetS
    logdetG = np.linalg.slogdet(G)[1]
    dof = st.n - p
    reml = -0.5 * (dof * np.log(rss / dof) + logdetV + logdetG)
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
    best = minimize(nll, z0, method="Nelder-Mead",
                    options={"xatol": 1e-3, "fatol": 1e-5, "maxiter": 300,
                             "initial_simplex": z0 + np.array([[0, 0], [3.0, 0], [0, 2.0]])})
    white = np.array([-30.0, 0.0])
    z = best.x if best.fun < nll(white) else white
    lam, rho = unpack(z)
    theta, G, rss, reml, dof = _solve(st, lam, rho)
    s2 = rss / dof
    return CellNoiseFit(theta, s2 * np.linalg.inv(G), s2, lam, rho, reml, dof)
