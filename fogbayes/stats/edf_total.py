r"""EDF and bias factors of TOTDEV, MTOTDEV, HTOTDEV and Theo1 (NIST SP 1065 sec. 5.3; Stable32 1.60).

``N`` phase points, averaging factor ``m``, ``alpha`` the rate-PSD exponent; a formula with no
positive value returns NaN. TOTDEV: Table 7, :math:`\nu = b N/m - c`; PM noise uses Table 5
(Stein). MTOTDEV/TTOTDEV: as Stable32 prints them (Greenhall's MDEV EDF for ``m < 10``, else a
line in ``1/m`` fitted to its PHASE.DAT intervals; Table 8 for alpha = 2, -1, -2).
HTOTDEV: ``(N/m)/(b0 + b1 m/N)`` for white FM, ``m >= 16``; Stein for PM; else Greenhall's
OHDEV EDF (conservative). Theo1: Table 11 (Howe & Tasset), ``tau = 0.75 m``. Bias: Htotvar/Hvar
(:data:`HTOTVAR_BIAS`), AVAR/Theo1 = a + b/tau^c, TOTVAR/AVAR = 1 - a tau/T.
"""

from __future__ import annotations

import math

import numpy as np

from .edf import edf_greenhall

TOTDEV_TABLE = {0: (1.50, 0.0), -1: (1.17, 0.22), -2: (0.93, 0.36)}
MTOTDEV_TABLE = {2: (1.90, 2.10), 1: (1.20, 1.40), 0: (1.10, 1.20), -1: (0.85, 0.50),
                 -2: (0.75, 0.31)}
#: (b, c) of Stable32's MTOTDEV/TTOTDEV EDF from m = 10 on (module doc), alpha 0 and 1
MTOTDEV_STABLE32 = {0: (1.3335, 1.894), 1: (1.7345, 2.993)}
#: below this m, Stable32 uses the MDEV EDF for MTOTDEV/TTOTDEV (not a T/tau bound: at T/tau
#: = 125 PHASE.DAT's m = 8 is Greenhall's, the 1 253-point Sr-87 record's m = 10 the line)
MTOTDEV_STABLE32_SWITCH = 10
#: (b0, b1) of the HTOTDEV EDF, white FM, m >= 16 (module doc)
HTOTDEV_WFM = (0.559, 1.004)
#: E[Htotvar] / Hvar per noise type (module doc); PM noise: 1
HTOTVAR_BIAS = {0: 0.995, -1: 0.851, -2: 0.771, -3: 0.717, -4: 0.679}
THEO1_BIAS = {2: (0.09, 0.74, 0.40), 1: (0.14, 0.82, 0.30), 0: (1.0, 0.0, 0.0),
              -1: (1.87, -1.05, 0.79), -2: (2.70, -1.53, 0.85)}
TOTVAR_BIAS = {-1: 1.0 / (3.0 * math.log(2.0)), -2: 0.750}


def _positive(v: float) -> float:
    return float(v) if np.isfinite(v) and v > 0 else float("nan")


def edf_avar_simple(alpha: int, m: int, N: int) -> float:
    """SP 1065 Table 5 (Stein) approximations for white and flicker PM (``N`` phase points)."""
    N, m = float(N), float(m)
    if alpha == 2:
        return _positive((N + 1) * (N - 2 * m) / (2 * (N - m)))
    if alpha == 1:
        a, b = (N - 1) / (2 * m), (2 * m + 1) * (N - 1) / 4
        if a <= 1 or b <= 1:  # a log turns negative: no EDF
            return float("nan")
        return _positive(math.exp(math.sqrt(math.log(a) * math.log(b))))
    raise ValueError(f"edf_avar_simple covers alpha = 2, 1 only, got {alpha}")


def edf_totdev(alpha: int, m: int, N: int) -> float:
    """TOTDEV EDF (module doc) for noise ``alpha`` at averaging factor ``m``, ``N`` phase points.

    Example:
        >>> round(edf_totdev(0, 10, 1001), 3)     # 1.5 * 1001 / 10
        150.15
    """
    alpha = int(alpha)
    if alpha in TOTDEV_TABLE:
        b, c = TOTDEV_TABLE[alpha]
        return _positive(b * N / m - c)
    return edf_avar_simple(alpha, m, N)


def edf_mtotdev(alpha: int, m: int, N: int) -> float:
    """MTOTDEV (and TTOTDEV) EDF, SP 1065 Table 8: ``b N / m - c``."""
    b, c = MTOTDEV_TABLE[int(alpha)]
    return _positive(b * N / m - c)


def edf_mtotdev_stable32(alpha: int, m: int, N: int) -> float:
    """MTOTDEV (and TTOTDEV) EDF as Stable32 1.60 computes it (module doc), ``N`` phase points.

    Example:
        >>> round(edf_mtotdev_stable32(0, 64, 1001), 2)    # 1.3335 * 1000 / 64 - 1.894
        18.94
    """
    alpha = int(alpha)
    if m < MTOTDEV_STABLE32_SWITCH:
        return _positive(edf_greenhall(alpha, 2, int(m), int(N), overlapping=True,
                                       modified=True))
    if alpha in MTOTDEV_STABLE32:
        b, c = MTOTDEV_STABLE32[alpha]
        return _positive(b * (N - 1) / m - c)
    return edf_mtotdev(alpha, m, N)


def edf_htotdev(alpha: int, m: int, N: int) -> float:
    """HTOTDEV EDF (module doc) for noise ``alpha``, ``N`` phase points (``N - 1`` rates).

    Example:
        >>> round(edf_htotdev(0, 32, 1001), 2)     # (1001/32) / (0.559 + 1.004 * 32/1001)
        52.92
    """
    alpha, m = int(alpha), int(m)
    if alpha == 0 and m >= 16:
        b0, b1 = HTOTDEV_WFM
        return _positive((N / m) / (b0 + b1 * m / N))
    if alpha in (2, 1):
        return edf_avar_simple(alpha, m, N)
    return _positive(edf_greenhall(alpha, 3, m, N, overlapping=True))


def htotvar_bias_ratio(alphas, ms) -> np.ndarray:
    """Hvar / E[Htotvar] (the factor that removes HTOTDEV's bias); 1 at m = 1 (OHDEV)."""
    return np.array([1.0 if int(m) == 1 else 1.0 / HTOTVAR_BIAS.get(int(a), 1.0)
                     for a, m in zip(alphas, ms)], dtype=float)


def edf_theo1(alpha: int, m: int, N: int) -> float:
    """Theo1 EDF (module doc), ``tau = 0.75 m``, ``N`` phase points."""
    t, N, alpha = 0.75 * float(m), float(N), int(alpha)
    if alpha == 2:
        v = 0.86 * (N + 1) * (N - 4.0 * t / 3.0) / (N - t) * t / (t + 1.14)
    elif alpha == 1:
        v = ((4.798 * N * N - 6.374 * N * t + 12.387 * t) / (math.sqrt(t + 36.6) * (N - t))
             * t / (t + 0.3))
    elif alpha == 0:
        v = ((4.1 * N + 0.8) / t - (3.1 * N + 6.5) / N) * t**1.5 / (t**1.5 + 5.2)
    elif alpha == -1:
        v = (2 * N * N - 1.3 * N * t - 3.5 * t) / (N * t) * t**3 / (t**3 + 2.3)
    elif alpha == -2:
        x = 4.4 * N
        v = (x - 2) / (2.9 * t) * ((x - 1) ** 2 - 8.6 * t * (x - 1) + 11.4 * t * t) / (x - 3) ** 2
    else:
        raise ValueError(f"Theo1 EDF covers alpha = -2..2, got {alpha}")
    return _positive(v)


_EDF = {"totdev": edf_totdev, "mtotdev": edf_mtotdev_stable32,
        "ttotdev": edf_mtotdev_stable32, "htotdev": edf_htotdev,
        "theo1": edf_theo1}


def edf_for_total_kind(alphas, ms, n: int, kind: str) -> np.ndarray:
    """EDF per averaging factor for ``n`` rate samples (``N = n + 1`` phase points)."""
    f = _EDF[kind]
    return np.array([f(int(a), int(m), n + 1) for a, m in zip(alphas, ms)], dtype=float)


def theo1_bias_ratio(alphas, ms) -> np.ndarray:
    """AVAR / Theo1 (the factor that removes Theo1's bias) for noise ``alpha`` at ``m``."""
    out = []
    for a, m in zip(alphas, ms):
        p, q, r = THEO1_BIAS[int(a)]
        out.append(p + q / (0.75 * float(m)) ** r)
    return np.array(out, dtype=float)


def totvar_bias_ratio(alphas, ms, n: int) -> np.ndarray:
    """AVAR / E[TOTVAR] = 1 / (1 - a m / n) for noise ``alpha`` (``T = n tau0``)."""
    return np.array([1.0 / (1.0 - TOTVAR_BIAS.get(int(a), 0.0) * float(m) / n)
                     for a, m in zip(alphas, ms)], dtype=float)
