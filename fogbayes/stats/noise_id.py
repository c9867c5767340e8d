r"""Power-law noise identification by the lag-1 autocorrelation (Riley & Greenhall 2004).

For cluster means of rate data (trend removed), :math:`\delta = r_1/(1+r_1)` of the ``d``-times
differenced series; differencing stops at the first ``d`` with :math:`\delta < 0.25`, and
:math:`\alpha = -\mathrm{round}(2\delta) - 2d` (rate PSD :math:`\propto f^\alpha`: +2 quantization,
0 angle random walk, -1 bias instability, -2 rate random walk). Below ~30 means the last alpha
is carried forward.
"""

from __future__ import annotations

import numpy as np

from .noise_id_sums import lag1_from_sums, lag1_sums, pair_means

MIN_POINTS = 30
#: From this many cluster means on, the lag-1 sums come from one compiled pass
#: (:mod:`~fogbayes.stats.noise_id_sums`); below it the NumPy form is as fast.
FUSED_MIN = 4096


def lag1_acf(z: np.ndarray) -> float:
    """Lag-1 autocorrelation, Riley (2004) eq. 2 (mean removed, biased normalisation)."""
    z = z - z.mean()
    den = float(np.dot(z, z))
    return float(np.dot(z[:-1], z[1:]) / den) if den > 0 else 0.0


def identify_alpha(y: np.ndarray, m: int, *, dmax: int = 2) -> int | None:
    """Integer alpha of rate data ``y`` at cluster size ``m``; None if too few points.

    A cluster that contains a NaN sample is dropped.
    """
    return _alpha_of_means(_block_means(np.asarray(y, float), 1, m), dmax)


def _block_means(z: np.ndarray, m_prev: int, m: int) -> np.ndarray:
    """Means of clusters of ``m`` samples from the means ``z`` of clusters of ``m_prev``."""
    f = m // m_prev
    n_cl = z.size // f
    if f == 2:  # octave grids: one compiled pass (pair_means), ~10x a reshape mean
        return pair_means(z) if z.size >= FUSED_MIN else 0.5 * (z[0:2 * n_cl:2] + z[1:2 * n_cl:2])
    return z[:n_cl] if f == 1 else z[:n_cl * f].reshape(n_cl, f).mean(axis=1)


def _alpha_of_means(z: np.ndarray, dmax: int) -> int | None:
    if z.size >= FUSED_MIN:  # one compiled pass for every d (noise_id_sums)
        sums = lag1_sums(z)
        if sums[0] < MIN_POINTS:
            return None
        r1 = [lag1_from_sums(sums, d) for d in range(dmax + 1)]
        if r1[0] is not None:  # else: a ramp-dominated series, the two-pass form below
            return _alpha_of_r1(r1, dmax)
    z = z[np.isfinite(z)]
    if z.size < MIN_POINTS:
        return None
    t = np.arange(z.size, dtype=float) - (z.size - 1) / 2.0  # centred: closed-form line fit
    z = z - z.mean() - t * (np.dot(t, z) / np.dot(t, t))  # remove the rate drift (Riley)
    d = 0
    while True:
        r1 = lag1_acf(z)
        delta = r1 / (1.0 + r1)
        if delta < 0.25 or d >= dmax:
            return int(-np.round(2 * delta) - 2 * d)
        z = np.diff(z)
        d += 1


def _alpha_of_r1(r1: list[float], dmax: int) -> int:
    """The same stopping rule as :func:`_alpha_of_means`, from the r1 of every order d."""
    for d in range(dmax + 1):
        delta = r1[d] / (1.0 + r1[d])
        if delta < 0.25 or d >= dmax:
            return int(-np.round(2 * delta) - 2 * d)
    raise AssertionError("unreachable: d reaches dmax")


def identify_alphas(y: np.ndarray, ms, *, kind: str = "oadev") -> np.ndarray:
    """Alpha per cluster size, carried forward where too few points remain.

    Clipped to the range where the EDF of ``kind`` exists (alpha + 2d > 1: -2..2 for the Allan
    variances, -4..2 for Hadamard).
    """
    y = np.asarray(y, dtype=float)
    hadamard = kind in ("ohdev", "hdev")
    lo = -4 if hadamard else -2
    dmax = 3 if hadamard else 2
    out, last = [], 0
    z, m_prev = y, 1
    for m in (int(v) for v in ms):
        # reuse the previous cluster means when m is a multiple (octave grids: O(n) in all)
        base, mb = (z, m_prev) if m % m_prev == 0 else (y, 1)
        z, m_prev = _block_means(base, mb, m), m
        a = _alpha_of_means(z, dmax)
        last = last if a is None else int(np.clip(a, lo, 2))
        out.append(last)
    return np.array(out, dtype=int)
