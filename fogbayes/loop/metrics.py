"""Before/after metrics of every loop step.

    rms             sqrt(mean_b rbar_b^2), rbar_b the residual's mean over 10 s blocks (deg/h)
                    (blocks restart at gaps; a short block at the end of a run is kept, so
                    bursts shorter than 10 s still count)
    bias_stability  paper 004 eq. 13 on 1 s windows of the compensated rate (deg/h),
                    :func:`fogbayes.stats.stability.bias_stability`
    elpd            PSIS-LOO elpd of the block means (:mod:`fogbayes.diagnose.elpd`)
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
