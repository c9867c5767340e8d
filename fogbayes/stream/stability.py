"""Bias and bias stability before/after (paper 004 eqs. 12-13) of a record read in chunks.

Streamed :func:`fogbayes.stats.stability.stability_report`: B0 = mean(F),
Bs(W) = sqrt(sum_b (m_b - m_bar)^2 / (n - 1)) over complete ``W``-second blocks
(:class:`.blocks.BlockSums`), sums taken about the first block's mean. O(1) memory.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..stats.stability import DEFAULT_WINDOWS, BeforeAfter, improvement_pct
from .blocks import BlockSums, Finished
from .scan import TimeScan

SERIES = ("before", "after")


class _Window:
    """Shifted sums of the complete blocks' means on one window length."""

    def __init__(self, scan: TimeScan, window_s: float):
        self.blocks = BlockSums(scan, window_s, len(SERIES))
        self.shift: np.ndarray | None = None
        self.s1 = np.zeros(len(SERIES))
        self.s2 = np.zeros(len(SERIES))
        self.n = 0

    def take(self, done: Finished) -> None:
        keep = self.blocks.complete(done) & (done.count > 0)
        if not keep.any():
            return
        m = done.sums[keep] / done.count[keep, None]
        if self.shift is None:
            self.shift = m[0].copy()
        d = m - self.shift
        self.s1 += d.sum(axis=0)
        self.s2 += (d * d).sum(axis=0)
        self.n += int(keep.sum())

    def std(self) -> np.ndarray | None:
        self.take(self.blocks.close())
        if self.n < 2:
            return None
        return np.sqrt(np.maximum(self.s2 - self.s1 ** 2 / self.n, 0.0) / (self.n - 1))


class StreamStability:
    """``add`` each chunk's rate before and after compensation (deg/h), then ``report``."""

    def __init__(self, scan: TimeScan, windows: Sequence[float] = DEFAULT_WINDOWS):
        # as check_window in memory: a window shorter than one step has no row
        self.windows = {float(w): _Window(scan, w) for w in windows
                        if float(w) >= scan.dt_median * (1 - 1e-9)}
        self.all_windows = tuple(float(w) for w in windows)
        self.total = np.zeros(len(SERIES))
        self.n = 0
        self.duration = float(scan.t_last - scan.t_first)

    def add(self, start: int, t: np.ndarray, before: np.ndarray, after: np.ndarray) -> None:
        """Rows ``start ..`` of the record: times and the rate before/after (deg/h)."""
        v = np.column_stack([np.asarray(before, float), np.asarray(after, float)])
        use = np.ones(t.size, bool)
        self.total += v.sum(axis=0)
        self.n += t.size
        for win in self.windows.values():
            win.take(win.blocks.add(start, t, v, use))

    def report(self) -> dict:
        """The dict of :func:`fogbayes.stats.stability.stability_report`."""
        rows = []
        for w in self.all_windows:
            sd = self.windows[w].std() if w in self.windows else None
            if sd is not None:
                b, a = float(sd[0]), float(sd[1])
                rows.append(BeforeAfter(w, b, a, improvement_pct(b, a))._asdict())
        mean = self.total / max(self.n, 1)
        return {"bias_before": float(mean[0]), "bias_after": float(mean[1]),
                "duration_s": self.duration, "stability": rows}
