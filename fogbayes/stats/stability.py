"""Bias and bias stability as paper 004 (and IEEE Std 952 users) define them.

Paper 004 eqs. 12-13, rate in deg/h: B0 = mean(F), Bs = sample standard deviation of the means
over consecutive ``window_s`` windows (:func:`fogbayes.preprocess.blocks.block_average`; never
across a gap, incomplete last block left out). Improvement % = 100 (Bs_before - Bs_after) / Bs_before.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import NamedTuple

import numpy as np

from ..errors import TooShortError
from ..preprocess.blocks import block_average

DEFAULT_WINDOWS = (1.0, 10.0, 100.0)


def window_means(time: np.ndarray, x: np.ndarray, window_s: float) -> np.ndarray:
    """Means of ``x`` over complete ``window_s`` blocks, cut at gaps (preprocess.blocks)."""
    return block_average(x, window_s, time=time, partial="drop").mean


def bias(rate_deg_h: np.ndarray) -> float:
    """B0 (deg/h): mean of a rate already divided by the scale factor (paper 004 eq. 12)."""
    return float(np.mean(np.asarray(rate_deg_h, dtype=float)))


def bias_stability(rate_deg_h: np.ndarray, time: np.ndarray, window_s: float = 1.0) -> float:
    """Bs (deg/h): std (n - 1) of the ``window_s`` averages of the rate (paper 004 eq. 13).

    Example:
        >>> t = np.arange(0.0, 100.0, 0.1)
        >>> round(bias_stability(np.where(t < 50, 1.0, -1.0), t, 1.0), 4)   # two levels
        1.005
    """
    means = window_means(time, rate_deg_h, window_s)
    if means.size < 2:
        raise TooShortError(f"bias stability on {window_s:g} s windows needs at least two "
                            f"full windows, the record gives {means.size}",
                            fix="use a shorter window or a longer record")
    return float(np.std(means, ddof=1))


def improvement_pct(before: float, after: float) -> float:
    """100 (before - after) / before: the paper's "bias stability improved by x %"."""
    return float(100.0 * (before - after) / before) if before > 0 else float("nan")


class BeforeAfter(NamedTuple):
    """Bias stability before and after compensation on one window length."""

    window_s: float
    before: float
    after: float
    improvement_pct: float


def stability_report(before: np.ndarray, after: np.ndarray, time: np.ndarray, *,
                     windows: Sequence[float] = DEFAULT_WINDOWS) -> dict:
    """B0 and Bs before/after on each window length that leaves at least two windows."""
    rows = []
    for w in windows:
        try:
            b, a = bias_stability(before, time, w), bias_stability(after, time, w)
        except TooShortError:
            continue  # fewer than two complete windows (e.g. 100 s in 5 s bursts): left out

        rows.append(BeforeAfter(float(w), b, a, improvement_pct(b, a))._asdict())
    return {"bias_before": bias(before), "bias_after": bias(after),
            "duration_s": float(time[-1] - time[0]), "stability": rows}


def segment_report(before: np.ndarray, after: np.ndarray, time: np.ndarray,
                   segments: Sequence = (), *,
                   windows: Sequence[float] = DEFAULT_WINDOWS) -> dict:
    """Full-temperature report plus one per segment (each soak and each ramp).

    ``segments``: objects with ``kind``, ``start``, ``stop`` (sample rows), e.g. from
    :func:`fogbayes.preprocess.segment_thermal`.
    """
    before, after, time = (np.asarray(a, dtype=float) for a in (before, after, time))
    out = {"full": stability_report(before, after, time, windows=windows), "segments": []}
    for seg in segments:
        sl = slice(int(seg.start), int(seg.stop))
        if seg.stop - seg.start < 2:
            continue
        rep = stability_report(before[sl], after[sl], time[sl], windows=windows)
        out["segments"].append({"kind": seg.kind, "start_s": float(time[sl][0]),
                                "stop_s": float(time[sl][-1]), **rep})
    return out
