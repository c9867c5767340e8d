"""Sample ACF and PACF with confidence bands (NumPy/SciPy; ACF by FFT, O(n log n)).

ACF: the biased estimator rho_k = c_k / c_0, c_k = (1/n) sum_t (x_t - xbar)(x_{t-k} - xbar).
PACF: Durbin-Levinson on rho (statsmodels' ``method="ldb"``). Bands at level 1 - alpha,
z = Phi^-1(1 - alpha/2): white noise +- z/sqrt(n); Bartlett (ACF, MA(k-1) null)
+- z sqrt((1 + 2 sum_{j<k} rho_j^2) / n).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..support.tails import norm_ppf


class Correlogram(NamedTuple):
    """lags (nlags+1,) from 0; values; band: half-width of the confidence band per lag."""

    lags: np.ndarray
    values: np.ndarray
    band: np.ndarray
    alpha: float


def autocovariance(x, nlags: int, *, demean: bool = True) -> np.ndarray:
    """c_0..c_nlags with divisor n (FFT, zero-padded to avoid circular wrap)."""
    x = np.asarray(x, dtype=float)
    if demean:
        x = x - x.mean()
    n = x.size
    m = 1 << int(np.ceil(np.log2(2 * n - 1)))
    f = np.fft.rfft(x, m)
    c = np.fft.irfft(f * np.conj(f), m)[: nlags + 1] / n
    return c


def acf(x, nlags: int = 40, *, alpha: float = 0.05, demean: bool = True) -> Correlogram:
    """Sample ACF rho_0..rho_nlags with Bartlett bands (see module docstring)."""
    x = np.asarray(x, dtype=float)
    nlags = int(min(nlags, x.size - 1))
    c = autocovariance(x, nlags, demean=demean)
    rho = c / c[0]
    z = norm_ppf(1 - alpha / 2)
    # cum[k] = sum_{j=1}^{k-1} rho_j^2 (0 for k = 0, 1)
    cum = np.concatenate([[0.0, 0.0], np.cumsum(rho[1:] ** 2)[:-1]])[: nlags + 1]
    band = z * np.sqrt((1 + 2 * cum) / x.size)
    band[0] = 0.0
    return Correlogram(np.arange(nlags + 1), rho, band, alpha)


def durbin_levinson(rho: np.ndarray) -> np.ndarray:
    """PACF phi_kk for k = 0..K from autocorrelations rho_0..rho_K (phi_00 = 1)."""
    K = rho.size - 1
    pacf = np.ones(K + 1)
    phi = np.zeros(0)
    v = 1.0
    for k in range(1, K + 1):
        a = (rho[k] - phi @ rho[1:k][::-1]) / v
        phi = np.concatenate([phi - a * phi[::-1], [a]])
        v *= 1.0 - a * a
        pacf[k] = a
    return pacf


def pacf(x, nlags: int = 40, *, alpha: float = 0.05, demean: bool = True) -> Correlogram:
    """Sample PACF phi_00..phi_KK (Durbin-Levinson) with the +- z / sqrt(n) band."""
    x = np.asarray(x, dtype=float)
    nlags = int(min(nlags, x.size // 2 - 1))
    rho = acf(x, nlags, alpha=alpha, demean=demean).values
    z = norm_ppf(1 - alpha / 2)
    band = np.full(nlags + 1, z / np.sqrt(x.size))
    band[0] = 0.0
    return Correlogram(np.arange(nlags + 1), durbin_levinson(rho), band, alpha)
