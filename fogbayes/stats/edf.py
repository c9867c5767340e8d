r"""Equivalent degrees of freedom (Greenhall & Riley 2004) and chi-square intervals.

An Allan-family variance estimate is distributed approximately as
:math:`\hat\sigma^2 \sim \sigma^2\,\chi^2_\nu/\nu` with the EDF :math:`\nu`. Greenhall's
general algorithm (Greenhall & Riley, "Uncertainty of stability variances based on finite
differences", PTTI 2003/2004, eqs. 7-10) is, for a power-law rate noise
:math:`S_y \propto f^\alpha`, a ``d``-th difference variance (d = 2 Allan, 3 Hadamard),
averaging factor ``m``, ``N`` phase points, filter factor ``F`` (``m`` unmodified, 1 modified)
and stride factor ``S`` (``m`` overlapping, 1 non-overlapping):

.. math::

    s_w(t) = \{-|t|,\ t^2\ln|t|,\ |t|^3,\ t^4\ln|t|,\ |t|^5,\ t^6\ln|t|,\ |t|^7\}
      \ \text{for}\ \alpha = 2, 1, \dots, -4

    s_x(t) = F^2\,[2 s_w(t) - s_w(t - 1/F) - s_w(t + 1/F)]
      \quad (F = \infty:\ s_x = s_w \text{ with } \alpha + 2)

    s_z(t) = \sum_{k=-d}^{d} (-1)^k \binom{2d}{d+k} s_x(t + k)

    L = m/F + m d,\quad M = 1 + \lfloor S (N - L)/m \rfloor,\quad J = \min(M, (d+1) S)

    \frac{1}{\nu} = \frac{1}{M s_z(0)^2}\Big[s_z(0)^2 + (1 - J/M)\,s_z(J/S)^2
        + 2\sum_{j=1}^{J-1} (1 - j/M)\,s_z(j/S)^2\Big].

The sum is evaluated exactly (not with Greenhall's tables) up to 20 000 terms and as a
Riemann sum with a coarser integer stride beyond (relative error ~1e-4). As in Greenhall's
"case 2b", unmodified variances with alpha <= 0 and ``m (d + 1) > 100`` use ``F = infinity``
(the continuous-time limit, which avoids cancellation in ``s_x`` at large ``m``).

Chi-square interval at confidence ``ci`` (NIST SP 1065 eq. 45):
:math:`\sigma^2_{lo} = \nu\hat\sigma^2/\chi^2_{\nu}((1+ci)/2)`,
:math:`\sigma^2_{hi} = \nu\hat\sigma^2/\chi^2_{\nu}((1-ci)/2)`.
"""

from __future__ import annotations

import numpy as np
from scipy import special, stats

D_OF_KIND = {"oadev": 2, "adev": 2, "mdev": 2, "ohdev": 3, "hdev": 3}
_EXACT_TERMS = 20_000
_F_INF_LIMIT = 100  # Greenhall's J_max: above m (d+1) > 100 use F = infinity (alpha <= 0)


def _sw(t: np.ndarray, alpha: int) -> np.ndarray:
    a = abs(t)
    if alpha % 2 == 0:  # -|t|, |t|^3, |t|^5, |t|^7
        return -a if alpha == 2 else a ** (3 - alpha)
    with np.errstate(divide="ignore", invalid="ignore"):
        v = t ** (3 - alpha) * np.log(a)
    return np.where(a == 0, 0.0, v)


def _sx(t: np.ndarray, F: float, alpha: int) -> np.ndarray:
    if np.isinf(F):
        return _sw(t, alpha + 2)
    return F * F * (2 * _sw(t, alpha) - _sw(t - 1.0 / F, alpha) - _sw(t + 1.0 / F, alpha))


def _sz(t: np.ndarray, F: float, alpha: int, d: int) -> np.ndarray:
    out = np.zeros_like(t, dtype=float)
    for k in range(-d, d + 1):
        out += (-1) ** k * special.comb(2 * d, d + k) * _sx(t + k, F, alpha)
    return out


def _filter_factor(alpha: int, d: int, m: int, modified: bool) -> float:
    if modified:
        return 1.0
    if alpha <= 0 and m * (d + 1) > _F_INF_LIMIT:
        return np.inf
    return float(m)


def _layout(d: int, m: int, n_phase: int, overlapping: bool, modified: bool):
    F = 1.0 if modified else float(m)
    S = float(m) if overlapping else 1.0
    L = m / F + m * d
    M = 1 + np.floor(S * (n_phase - L) / m)
    J = min(M, (d + 1) * S)
    return S, M, J


def basic_sum(sz_of_t, J: float, M: float, S: float) -> float:
    """Greenhall eq. 10 for an ``s_z`` given as a function of t (exact or strided)."""
    s0 = float(sz_of_t(np.zeros(1))[0])
    total = s0 ** 2 + (1 - J / M) * float(sz_of_t(np.array([J / S]))[0]) ** 2
    n_inner = int(J) - 1
    if n_inner > 0:
        q = max(1, -(-n_inner // _EXACT_TERMS))
        j = np.arange(q, n_inner + 1, q, dtype=float)
        # midpoint-weighted strided sum: each sampled j stands for q integers
        total += 2 * q * float(np.sum((1 - j / M) * sz_of_t(j / S) ** 2))
    return total


def edf_greenhall(alpha: int, d: int, m: int, n_phase: int, *, overlapping: bool = True,
                  modified: bool = False) -> float:
    """EDF of a d-th difference variance for pure power-law noise ``alpha``.

    Example:
        >>> round(edf_greenhall(0, 2, 1, 1001), 1)   # white rate, OADEV, m = 1: ~ 2/3 (N - 2)
        666.3
    """
    return edf_mixture({int(alpha): 1.0}, d, m, n_phase, overlapping=overlapping,
                       modified=modified)


def edf_mixture(weights: dict[int, float], d: int, m: int, n_phase: int, *,
                overlapping: bool = True, modified: bool = False) -> float:
    """EDF for a sum of independent power-law noises (``{alpha: variance share at this m}``).

    The filtered-noise autocovariances add, so :math:`s_z = \\sum_p w_p s_{z,p}/s_{z,p}(0)`
    goes into the same basic sum; a single noise gives :func:`edf_greenhall`.
    """
    S, M, J = _layout(d, m, n_phase, overlapping, modified)
    if M < 1:
        return float("nan")
    parts = [(w, alpha, _filter_factor(alpha, d, m, modified))
             for alpha, w in weights.items() if w > 0]
    norms = [float(_sz(np.zeros(1), F, a, d)[0]) for _, a, F in parts]

    def sz(t):
        return sum(w * _sz(t, F, a, d) / z0 for (w, a, F), z0 in zip(parts, norms))

    s0 = float(sz(np.zeros(1))[0])
    return M * s0 ** 2 / basic_sum(sz, J, M, S)


def edf_for_kind(alphas, ms, n: int, kind: str) -> np.ndarray:
    """Greenhall EDF per cluster size for rate data of length ``n`` (``n + 1`` phase points)."""
    d = D_OF_KIND[kind]
    overlapping = kind in ("oadev", "mdev", "ohdev")
    modified = kind == "mdev"
    return np.array([edf_greenhall(int(a), d, int(m), n + 1, overlapping=overlapping,
                                   modified=modified) for a, m in zip(alphas, ms)])


def chi2_interval(var: np.ndarray, edf: np.ndarray, ci: float = 0.9):
    """(low, high) bounds of the variance at confidence ``ci`` (two-sided, equal tails)."""
    var, edf = np.asarray(var, float), np.asarray(edf, float)
    lo = edf * var / stats.chi2.ppf(0.5 + ci / 2, edf)
    hi = edf * var / stats.chi2.ppf(0.5 - ci / 2, edf)
    return lo, hi
