r"""Noise identification from fewer than 30 cluster means: the B1 ratio and R(n) (Stable32).

Where the lag-1 autocorrelation (:mod:`~fogbayes.stats.noise_id`) has too few cluster means,
Stable32 1.60 identifies the noise of MTOTDEV, TTOTDEV and HTOTDEV from two variance ratios
(Barnes 1974; Howe, Beard, Greenhall & Riley 2000; NIST SP 1065 sec. 5.6):

* **B1** = :math:`s^2 / \sigma^2_y(\tau)`: the variance of the ``N`` means of ``m`` samples
  (normalised by ``N``) over the non-overlapping Allan variance of the same means. Its
  expectation for phase-PSD exponent ``mu`` is

  .. math::

      B_1(N, \mu) = \frac{N(N+1)}{6}\ (\mu = 2),\quad \frac{N}{2}\ (1),\quad
      \frac{N \ln N}{2 (N-1) \ln 2}\ (0),\quad 1\ (-1),\quad \frac{N^2 - 1}{1.5 N (N-1)}\ (-2),

  and ``mu`` is the first of 2, 1, 0, -1 whose boundary the measured ratio exceeds (the
  arithmetic mean of the neighbouring expectations between 2 and 1, the geometric mean
  elsewhere), else -2. ``alpha = -mu - 1`` for ``mu >= -1``.
* ``mu = -2`` (white or flicker PM): **R(n)** = MVAR / AVAR (the overlapping modified Allan
  variance over the same non-overlapping AVAR) decides, against the geometric mean of its
  expectations ``1/m`` (white PM, alpha 2) and ``3.37 / (1.04 + 3 ln(pi m))`` (flicker PM,
  alpha 1; NIST TN 1337 with ``f_h = 1 / (2 tau0)``).

Every alpha that Stable32 prints for MTOTDEV, TTOTDEV and HTOTDEV below 30 cluster means on
PHASE.DAT (m = 64 ... 256) follows from this rule; normalising ``s^2`` by ``N - 1`` does not.
With so few means B1 is noisy: white FM is read as flicker PM in 36 %, 53 %, 71 % of
1 000-sample records at m = 64, 128, 256 (15, 7, 3 means), as Stable32 reads PHASE.DAT.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["b1_expected", "b1_rn_alpha"]


def b1_expected(N: int, mu: int) -> float:
    """Expected B1 ratio of ``N`` frequency means for phase-PSD exponent ``mu`` (module doc)."""
    N = float(N)
    if mu == 2:
        return N * (N + 1.0) / 6.0
    if mu == 1:
        return N / 2.0
    if mu == 0:
        return N * math.log(N) / (2.0 * (N - 1.0) * math.log(2.0))
    if mu == -1:
        return 1.0
    if mu == -2:
        return (N * N - 1.0) / (1.5 * N * (N - 1.0))
    raise ValueError(f"B1 is tabulated for mu = -2..2, got {mu}")


def _mu_of_b1(b1: float, N: int) -> int:
    e = {mu: b1_expected(N, mu) for mu in (2, 1, 0, -1, -2)}
    for mu in (2, 1, 0, -1):
        bound = 0.5 * (e[mu] + e[mu - 1]) if mu == 2 else math.sqrt(e[mu] * e[mu - 1])
        if b1 > bound:
            return mu
    return -2


def _modified_avar(y: np.ndarray, m: int) -> float:
    """Overlapping modified Allan variance of rate ``y`` at ``m`` (N - 3m + 1 terms)."""
    x = np.concatenate([[0.0], np.cumsum(y - np.mean(y))])  # phase, unit y * tau0
    s = np.concatenate([[0.0], np.cumsum(x)])
    k = x.size - 3 * m + 1
    j = np.arange(k)
    block = lambda a: s[a + m] - s[a]  # noqa: E731  (sum of m phase points from a)
    d = block(j + 2 * m) - 2.0 * block(j + m) + block(j)
    return float(np.mean(d * d) / (2.0 * m**4))


def b1_rn_alpha(y, m: int, *, lo: int = -2) -> int | None:
    """Alpha (rate-PSD exponent, clipped to ``lo``..2) of rate ``y`` at ``m`` by B1 and R(n).

    Needs at least 3 means of ``m`` samples and ``3 m <= n + 1``; None where the means do
    not change (no Allan variance to divide by).

    Example:
        >>> rng = np.random.default_rng(0)
        >>> b1_rn_alpha(rng.normal(size=1000), 100), b1_rn_alpha(np.diff(rng.normal(size=1001)), 100)
        (0, 2)
    """
    y = np.asarray(y, dtype=float)
    z = y[: (y.size // m) * m].reshape(-1, m).mean(axis=1)
    if z.size < 3:
        raise ValueError(f"B1 needs at least 3 means of {m} samples, got {z.size}")
    avar = 0.5 * float(np.mean(np.diff(z) ** 2))
    if not avar > 0:
        return None
    mu = _mu_of_b1(float(np.var(z)) / avar, z.size)
    if mu > -2:
        return max(lo, -mu - 1)
    rn = _modified_avar(y, m) / avar
    bound = math.sqrt((1.0 / m) * 3.37 / (1.04 + 3.0 * math.log(math.pi * m)))
    return 1 if rn > bound else 2
