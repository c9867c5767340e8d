"""Residual whiteness: paper 002's rho_a,2 and rho_ax,3, and the Ljung-Box portmanteau test.

Paper 002 eqs. 11-12: rho_a,2 = sum a_t a_{t-2} / sum a_t^2, rho_ax,3 = sum a_t x_{t-3} /
sqrt(sum a_t^2 sum x_{t-3}^2), each ~N(0, 1/n) under white residuals. Ljung-Box (1978):
Q = n(n+2) sum_{k<=h} r_k^2/(n-k), p = P(chi2_{h-p-q} > Q). ``white`` needs all three at alpha/3.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .acf import acf
from ..support.tails import chi2_sf, norm_ppf


class Whiteness(NamedTuple):
    """rho_a2, rho_ax3 (paper), their level-alpha band z/sqrt(n), Ljung-Box Q, dof, p-value,
    lags and the verdict ``white`` (all three checks pass at alpha/3 each)."""

    rho_a2: float
    rho_ax3: float
    band: float
    ljung_box_q: float
    ljung_box_dof: int
    ljung_box_p: float
    lags: int
    alpha: float
    white: bool


def rho_a2(a) -> float:
    """Paper eq. 11: lag-2 autocorrelation of the residuals, sum over t = 3..N (1-based)."""
    a = np.asarray(a, dtype=float)
    return float(np.dot(a[2:], a[:-2]) / np.dot(a[2:], a[2:]))


def rho_ax3(a, x) -> float:
    """Paper eq. 12: correlation of a_t with x_{t-3}, sums over t = 4..N (1-based)."""
    a, x = np.asarray(a, dtype=float), np.asarray(x, dtype=float)
    return float(np.dot(a[3:], x[:-3]) / np.sqrt(np.dot(a[3:], a[3:]) * np.dot(x[:-3], x[:-3])))


def ljung_box(a, lags: int = 20, *, fitted_params: int = 0) -> tuple[float, int, float]:
    """(Q, dof, p-value) of the Ljung-Box test on residuals a; dof = lags - fitted_params."""
    a = np.asarray(a, dtype=float)
    n = a.size
    r = acf(a, lags).values[1:]
    q = float(n * (n + 2) * np.sum(r * r / (n - np.arange(1, lags + 1))))
    dof = int(lags - fitted_params)
    if dof < 1:
        raise ValueError(f"Ljung-Box needs lags > fitted parameters ({lags} <= {fitted_params})")
    return q, dof, float(chi2_sf(q, dof))


def whiteness(a, x, *, p: int = 0, q: int = 0, lags: int | None = None,
              alpha: float = 0.05) -> Whiteness:
    """All whiteness checks of residuals a of an ARMA(p, q) fitted to x.

    ``lags`` defaults to min(20, n // 5) but at least p + q + 1.
    """
    a = np.asarray(a, dtype=float)
    n = a.size
    h = lags if lags is not None else max(min(20, n // 5), p + q + 1)
    qs, dof, pval = ljung_box(a, h, fitted_params=p + q)
    ra, rx = rho_a2(a), rho_ax3(a, x)
    band = float(norm_ppf(1 - alpha / 2) / np.sqrt(n))
    bonf = float(norm_ppf(1 - alpha / 6) / np.sqrt(n))  # alpha/3 per check, two-sided
    white = bool(abs(ra) < bonf and abs(rx) < bonf and pval > alpha / 3)
    return Whiteness(ra, rx, band, qs, dof, pval, h, alpha, white)
