r"""Theo1 variance of rate data (NIST SP 1065 sec. 5.2.14, eq. 30; Howe & Tasset 2004).

For even ``m``, ``2 <= m <= N - 1``, at :math:`\tau = 0.75\,m\,\tau_0`:
:math:`\mathrm{Theo1} = \frac{1}{0.75(N-m)(m\tau_0)^2}\sum_{i}\sum_{\delta=0}^{m/2-1}
\frac{[(x_i - x_{i-\delta+m/2}) + (x_{i+m} - x_{i+\delta+m/2})]^2}{m/2-\delta}`.
Unbiased for white FM; other noises take :func:`~fogbayes.stats.edf_total.theo1_bias_ratio`.
Sums: :func:`~fogbayes.stats.total_loops.theo1_sums`. TheoBR/TheoH: :mod:`~fogbayes.stats.theoh`.
"""

from __future__ import annotations

import numpy as np

from ..errors import FogbayesError, TooShortError
from .total_loops import phase_samples, theo1_sums

__all__ = ["theo1_limit", "theo1_variance"]


def theo1_limit(n: int) -> int:
    """Largest Theo1 averaging factor for ``n`` rate samples: the largest even m <= n."""
    return n - n % 2


def theo1_variance(y, ms) -> tuple[np.ndarray, np.ndarray]:
    """``(var, count)`` of Theo1 at even averaging factors ``ms`` (tau = 0.75 m / fs).

    Args:
        y: rate samples, 1-D, finite (no gaps).
        ms: even averaging factors, ``2 <= m <= n``.

    Returns:
        ``var`` in the unit of ``y`` squared (allantools' ``theo1(..., data_type="freq")``
        squared, to rounding) and ``count`` = ``N - m`` outer terms (allantools counts the
        ``(N - m) m / 2`` inner terms).

    Example:
        >>> y = np.random.default_rng(0).normal(size=4000)    # white FM: Theo1 ~ AVAR
        >>> var, count = theo1_variance(y, [16])
        >>> bool(abs(var[0] * 12 - 1) < 0.1), int(count[0])   # AVAR(tau = 12) = 1/12
        (True, 3985)
    """
    y = np.ascontiguousarray(y, dtype=np.float64)
    if y.ndim != 1:
        raise FogbayesError(f"Theo1 needs 1-D rate data, got shape {y.shape}",
                            fix="pass one sensor as (n,)")
    ms = np.asarray(ms, dtype=np.int64).reshape(-1)
    n = y.size
    top = theo1_limit(n)
    if ms.size == 0 or ms.min() < 2 or ms.max() > top or (ms % 2).any():
        raise TooShortError(f"Theo1 averaging factors must be even and lie in 2..{top} for "
                            f"{n} samples, got {ms.tolist()}", argument="taus",
                            fix="pass even cluster sizes (tau = 0.75 m / fs)")
    S = phase_samples(y, float(np.mean(y)))
    sums = np.zeros(ms.size)
    theo1_sums(S, ms, sums)
    N = n + 1
    m = ms.astype(float)
    count = (N - m).astype(float)
    return sums / (0.75 * count * m * m), count
