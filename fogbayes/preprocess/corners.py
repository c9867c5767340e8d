"""Corners of a chamber programme in the temperature rate, found and kept.

Behind a first-order lag, d2T/dt2 jumps at each corner of a piecewise-linear set point. At
every block the fit T = a + b d + c d^2 + c_jump d^2 [d >= 0] (d = t - t_j) gains over the
quadratic RSS / s2 ~ chi2_1 without a corner; corners are local maxima above the Bonferroni
threshold at alpha / N (alpha = 0.01), refined to dt/8, and within W/2 + dt the rate is the
fitted derivative. Block means must sit at block centres (``covariates.centred_block_temperature``).
"""

from __future__ import annotations

import numpy as np

from ..support.tails import chi2_isf, chi2_ppf

#: family-wise probability of a false corner in a record without any
ALPHA = 0.01


def _kinked_design(d: np.ndarray) -> np.ndarray:
    """Columns 1, d, d^2, d^2 [d >= 0]: a quadratic whose curvature jumps at d = 0."""
    return np.column_stack([np.ones_like(d), d, d * d, np.where(d >= 0, d * d, 0.0)])


def corner_gains(Tb: np.ndarray, n: int) -> np.ndarray:
    """Standardised RSS gain of a corner at every block (0 within n of either end)."""
    N = Tb.size
    z = np.zeros(N)
    if N < 2 * n + 1:
        return z
    x = np.arange(-n, n + 1, dtype=float)
    q, _ = np.linalg.qr(np.vander(x, 3, increasing=True))
    jump = np.where(x >= 0, x * x, 0.0)
    qj = jump - q @ (q.T @ jump)
    qj /= np.linalg.norm(qj)
    r = Tb - Tb.mean()  # centred: the window sums of squares stay well conditioned
    gain = np.correlate(r, qj, mode="valid") ** 2
    total = np.correlate(r * r, np.ones(2 * n + 1), mode="valid")
    rss = total - sum(np.correlate(r, q[:, k], mode="valid") ** 2 for k in range(3)) - gain
    s2 = float(np.median(rss)) / float(chi2_ppf(0.5, 2 * n + 1 - 4))  # chi2 median
    if not s2 > 0.0:
        return z
    z[n:N - n] = gain / s2
    return z


def find_corners(tb: np.ndarray, Tb: np.ndarray, n: int, alpha: float = ALPHA):
    """Corners as (time, beta), beta = (a, b, c, c_jump) of the kinked fit around each."""
    z = corner_gains(Tb, n)
    N, dt = Tb.size, float(tb[1] - tb[0]) if Tb.size > 1 else 1.0
    threshold = chi2_isf(alpha / max(N, 1), 1)
    out = []
    for j in np.flatnonzero(z > threshold):
        if z[j] < z[max(j - n, 0):j + n + 1].max():
            continue  # not the strongest corner within a window
        best = None
        for k in tb[j] + np.arange(-8, 9) / 8.0 * dt:
            span = np.abs(tb - k) <= n * dt + 1e-9 * dt
            X = _kinked_design(tb[span] - k)
            beta, *_ = np.linalg.lstsq(X, Tb[span], rcond=None)
            rss = float(np.sum((Tb[span] - X @ beta) ** 2))
            if best is None or rss < best[0]:
                best = (rss, float(k), beta)
        out.append(best[1:])
    return out


def corner_reach(tb: np.ndarray, n: int) -> float:
    """How far (s) from a corner the kinked fit's slope replaces the smooth one."""
    return (0.5 * n + 1.0) * float(tb[1] - tb[0]) if tb.size > 1 else 0.0


def replace_near_corners(corners, half: float, t: np.ndarray, rate: np.ndarray) -> np.ndarray:
    """``rate`` (deg C/s at times ``t``) with each corner's kinked-fit slope within ``half``."""
    out = np.array(rate, dtype=float, copy=True)
    for k, beta in corners:
        near = np.abs(t - k) <= half
        d = t[near] - k
        out[near] = beta[1] + 2.0 * beta[2] * d + 2.0 * beta[3] * np.maximum(d, 0.0)
    return out
