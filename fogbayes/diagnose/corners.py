"""Corners of a chamber programme in the temperature rate, found and kept.

A chamber follows a piecewise-linear set point; a sensor behind a first-order lag tau follows
it with tau dT/dt = T_chamber - T. So dT/dt is continuous, but its slope d2T/dt2 jumps by
(change of ramp rate) / tau at every corner of the programme. A centred Savitzky-Golay slope
over a window W rounds each such corner over +-W/2: on the 16x hysteresis records of the
loop's sweep its error reached 0.04 deg C/min just where dT/dt crosses zero, against a tanh
scale r0 of 0.05 deg C/min.

Scan, at every block j of the block-mean temperature (n blocks = one window each side)::

    T(t) = a + b d + c d^2 + c_jump d^2 [d >= 0],   d = t - t_j

is value- and slope-continuous at t_j with a free curvature jump (one column more than the
quadratic). Its RSS gain over the quadratic, divided by the block noise variance s2, is
chi2_1 without a corner. Corners are local maxima (within +-n blocks) of the gain above
the Bonferroni threshold chi2_1 upper quantile at alpha / N (alpha = 0.01): a record
without corners gets a false one with probability < 1 %. s2 is the median of the
four-column window RSS over the median of chi2_(2n+1-4), robust to the corners themselves.
Each corner is refined to dt/8 within one block, and within W/2 + dt of it the rate is the
fitted derivative b + 2 c d + 2 c_jump max(d, 0), which keeps the kink. A strong corner may
be followed by weaker ones where the lag's curvature decays (exp(-t / tau) is not quadratic
over two windows); there the kinked fit is simply the better local fit.

The block means must sit at their block centres (``covariates.centred_block_temperature``): on a
steep ramp a mean time off the centre by one sample looks like a corner.

Measured on a lagged two-ramp programme (tests/test_diagnose_corners.py, 0.01 deg C noise):
max rate error 0.036-0.037 -> 0.007-0.008 deg C/min at 10 Hz, 0.042-0.045 -> 0.022-0.026 at
2 Hz, 0.045-0.049 -> 0.021-0.034 at 1 Hz (seeds 0 and 1); on a smooth sinusoidal
temperature nothing is replaced.
"""

from __future__ import annotations

import numpy as np
from scipy.stats import chi2

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
    s2 = float(np.median(rss)) / chi2.median(2 * n + 1 - 4)
    if not s2 > 0.0:
        return z
    z[n:N - n] = gain / s2
    return z


def find_corners(tb: np.ndarray, Tb: np.ndarray, n: int, alpha: float = ALPHA):
    """Corners as (time, beta), beta = (a, b, c, c_jump) of the kinked fit around each."""
    z = corner_gains(Tb, n)
    N, dt = Tb.size, float(tb[1] - tb[0]) if Tb.size > 1 else 1.0
    threshold = chi2.isf(alpha / max(N, 1), 1)
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

