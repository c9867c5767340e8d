"""The loop's 10 s RMS (:func:`fogbayes.loop.metrics.block_rms`) of a record read in chunks.

rms = sqrt(mean_b m_b^2), m_b the mean of block b's unflagged samples
(:func:`fogbayes.preprocess.blocks.block_average`, ``partial="keep"``, by :class:`.blocks.BlockSums`).
"""

from __future__ import annotations

import numpy as np

from .blocks import BlockSums, Finished
from .scan import TimeScan


class StreamBlockRMS:
    """Accumulate block means of several series (``add`` each chunk, then ``rms``)."""

    def __init__(self, scan: TimeScan, names: tuple[str, ...], window_s: float = 10.0):
        self.names = names
        self.blocks = BlockSums(scan, window_s, len(names))
        self.sq = np.zeros(len(names))             # sum of m_b^2 over finished blocks
        self.lin = np.zeros(len(names))            # sum of m_b
        self.n_blocks = 0
        self.total = np.zeros(len(names))          # sum over all unflagged samples
        self.n_used = 0

    def _finish(self, done: Finished) -> None:
        ok = done.count > 0
        m = done.sums[ok] / done.count[ok, None]
        self.sq += np.sum(m * m, axis=0)
        self.lin += np.sum(m, axis=0)
        self.n_blocks += int(ok.sum())

    def add(self, start: int, t: np.ndarray, values: dict, use: np.ndarray) -> None:
        """Rows ``start ..`` of the record: times, the named series, the unflagged mask."""
        v = np.column_stack([np.asarray(values[nm], float) for nm in self.names])
        self.total += v[use].sum(axis=0)
        self.n_used += int(use.sum())
        self._finish(self.blocks.add(start, t, v, use))

    def rms(self) -> dict[str, float]:
        """RMS of the block means per series, and of ``after`` about its overall mean."""
        self._finish(self.blocks.close())
        n = max(self.n_blocks, 1)
        out = {nm: float(np.sqrt(self.sq[j] / n)) for j, nm in enumerate(self.names)}
        if "after" in self.names:
            j = self.names.index("after")
            c = self.total[j] / max(self.n_used, 1)
            # mean_b (m_b - c)^2 = mean_b m_b^2 - 2 c mean_b m_b + c^2
            out["after_about_mean"] = float(np.sqrt(max(
                (self.sq[j] - 2 * c * self.lin[j]) / n + c * c, 0.0)))
        return out
