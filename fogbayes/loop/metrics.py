"""Before/after metrics of every loop step.

``rms``: sqrt(mean_b rbar_b^2) over 10 s blocks (restarting at gaps), deg/h; ``bias_stability``:
paper 004 eq. 13 on 1 s windows (:func:`fogbayes.stats.stability.bias_stability`); ``elpd``:
PSIS-LOO of the block means (:mod:`fogbayes.loop.elpd`).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..errors import TooShortError
from ..stats.stability import bias_stability
from ..preprocess.blocks import block_average

RMS_WINDOW_S = 10.0
BS_WINDOW_S = 1.0


class Metrics(NamedTuple):
    rms: float
    bias_stability: float | None
    elpd: float
    elpd_se: float


def block_rms(time: np.ndarray, residual: np.ndarray, outlier: np.ndarray,
              window_s: float = RMS_WINDOW_S) -> float:
    """RMS of the residual's ``window_s`` block means (outliers left out)."""
    b = block_average(residual, window_s, time=time, partial="keep", mask=outlier)
    m = b.mean[np.isfinite(b.mean)]
    return float(np.sqrt(np.mean(m * m)))


def stability(time: np.ndarray, residual: np.ndarray, outlier: np.ndarray) -> float | None:
    """Bias stability of the compensated rate (residual) on 1 s windows; None if too short."""
    keep = ~outlier
    try:
        return bias_stability(residual[keep], time[keep], BS_WINDOW_S)
    except TooShortError:
        return None
