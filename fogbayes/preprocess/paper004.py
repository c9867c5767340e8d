"""Paper 004's smoothing: rate averaged over 1 s, temperature over 10 s, on one 1 s grid.

Rates: means over complete 1 s blocks (``mask`` leaves flagged samples out); temperatures:
10 s blocks of the same grid (:mod:`.blocks`), all samples. ``align="hold"`` (default): each 1 s
row gets its 10 s block's mean and the backward difference of 10 s means; ``"interp"``:
linear interpolation, differences at block-pair midpoints.
"""

from __future__ import annotations

import dataclasses
from typing import NamedTuple

import numpy as np

from ..errors import FogbayesError
from ._checks import GAP_FACTOR, check_window
from .blocks import _mask, block_index, group_mean, group_starts, sample_grid
from .temperature_rate import ls_slope, rates_from_means


class Paper004Smoothed(NamedTuple):
    """Result of :func:`paper004_smoothing`.

    recording: the 1 s Recording (output and input rate 1 s means; temperatures 10 s means
        aligned to the 1 s rows).
    count: (B,) samples in each 1 s mean.
    start, stop: (B,) input sample range of each row.
    temperature_rate: (B, k) deg C/s per temperature channel, from the 10 s means.
    """

    recording: object
    count: np.ndarray
    start: np.ndarray
    stop: np.ndarray
    temperature_rate: np.ndarray


def paper004_smoothing(rec, *, mask=None, rate_window_s: float = 1.0,
                       temperature_window_s: float = 10.0, align: str = "hold",
                       gap_factor: float = GAP_FACTOR) -> Paper004Smoothed:
    """Smooth a Recording as paper 004 does (see the module doc for the alignment).

    Args:
        rec: a :class:`fogbayes.data.Recording` (e.g. 200 Hz).
        mask: optional bool (n,), True for output samples to leave out (outlier flags).
        rate_window_s: output block (s), 1 in the paper.
        temperature_window_s: temperature block (s), 10 in the paper; a whole multiple of
            ``rate_window_s``.
        align: "hold" or "interp".
    """
    if align not in ("hold", "interp"):
        raise FogbayesError(f"align must be 'hold' or 'interp', got {align!r}", column="align",
                            fix="pass align='hold' (the paper) or align='interp'")
    t = rec.time
    ratio = float(temperature_window_s) / float(rate_window_s)
    m = int(round(ratio))
    if m < 1 or abs(ratio - m) > 1e-9 * ratio:
        raise FogbayesError(f"temperature_window_s={temperature_window_s:g} s is not a whole "
                            f"multiple of rate_window_s={rate_window_s:g} s",
                            column="temperature_window_s",
                            fix="use e.g. rate_window_s=1.0 and temperature_window_s=10.0")
    check_window(temperature_window_s, t, name="temperature_window_s")
    bi = block_index(t, rate_window_s, partial="drop", gap_factor=gap_factor)
    cols = rec.output[:, None]
    if rec.input_rate is not None:
        cols = np.hstack([cols, rec.input_rate[:, None]])
    tm, means, cnt = group_mean(bi.block, bi.start.size, t, cols, _mask(mask, rec.n))

    # 10 s groups: ten consecutive 1 s grid cells of the same run (k // m), so they nest.
    seg, k, _ = sample_grid(t, float(rate_window_s), gap_factor)
    gid = group_starts(seg, k // m)
    n_groups = int(gid[-1]) + 1
    g_time, g_temp, _ = group_mean(gid, n_groups, t, rec.temperatures)
    g_seg = seg[np.r_[0, np.flatnonzero(np.diff(gid)) + 1]]
    q_group = gid[bi.start]  # the 10 s block each 1 s row lies in
    q_seg = bi.segment

    n_ch = rec.temperatures.shape[1]
    temps = np.empty((bi.start.size, n_ch))
    rates = np.empty((bi.start.size, n_ch))
    for j in range(n_ch):
        if align == "hold":
            temps[:, j] = g_temp[q_group, j]
        else:
            for s in np.unique(q_seg):
                qs, gs = q_seg == s, g_seg == s
                temps[qs, j] = np.interp(tm[qs], g_time[gs], g_temp[gs, j])

        def fallback(s, j=j):
            idx = seg == s
            return ls_slope(t[idx], rec.temperatures[idx, j])

        rates[:, j] = rates_from_means(g_seg, g_time, g_temp[:, j], q_seg, tm, q_group,
                                       align, fallback)

    keep = cnt > 0  # rows whose samples were all flagged have nothing to average
    meta = dataclasses.replace(
        rec.meta, sample_rate=1.0 / float(rate_window_s),
        extra={**rec.meta.extra, "paper004_smoothing": {
            "rate_window_s": float(rate_window_s),
            "temperature_window_s": float(temperature_window_s), "align": align}})
    out = rec.replace(time=tm[keep], output=means[keep, 0], temperatures=temps[keep],
                      input_rate=means[keep, 1] if rec.input_rate is not None else None,
                      meta=meta)
    return Paper004Smoothed(out, cnt[keep], bi.start[keep], bi.stop[keep], rates[keep])
