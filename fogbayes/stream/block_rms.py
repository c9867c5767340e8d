"""The loop's 10 s RMS (:func:`fogbayes.loop.metrics.block_rms`) of a record read in chunks.

    rms = sqrt(mean_b m_b^2),  m_b the mean of block b's unflagged samples

Blocks as :func:`fogbayes.preprocess.blocks.block_average` with ``partial="keep"``: each run
between gaps (the time scan's runs, the same gap rule) is cut into ``window_s`` blocks from
its first sample, k = floor((t - t_run + slack) / window_s), slack = max(1e-3 median step,
16 ulp of the largest |t|); a block whose samples are all flagged has no mean and is left
out. Blocks are contiguous in sample order, so each is finished as soon as the next one
starts: memory O(1), whatever the record's length. The sums differ from the in-memory
ones only in rounding (a block cut by a chunk boundary is summed in two parts).
"""

from __future__ import annotations

import numpy as np

from .scan import TimeScan


class StreamBlockRMS:
    """Accumulate block means of several series (``add`` each chunk, then ``rms``)."""

    def __init__(self, scan: TimeScan, names: tuple[str, ...], window_s: float = 10.0):
        self.w, self.names = float(window_s), names
        self.slack = max(1e-3 * scan.dt_median, 16 * float(np.spacing(scan.t_absmax)))
        self.bounds, self.run_t0 = scan.bounds, scan.run_t0
        self.open_key = None                       # (run, k) of the block still open
        self.open_sum = np.zeros(len(names))
        self.open_cnt = 0
        self.sq = np.zeros(len(names))             # sum of m_b^2 over finished blocks
        self.lin = np.zeros(len(names))            # sum of m_b
        self.n_blocks = 0
        self.total = np.zeros(len(names))          # sum over all unflagged samples
        self.n_used = 0

    def _finish(self, sums: np.ndarray, cnt: np.ndarray) -> None:
        ok = cnt > 0
        m = sums[ok] / cnt[ok, None]
        self.sq += np.sum(m * m, axis=0)
        self.lin += np.sum(m, axis=0)
        self.n_blocks += int(ok.sum())

    def add(self, start: int, t: np.ndarray, values: dict, use: np.ndarray) -> None:
        """Rows ``start ..`` of the record: times, the named series, the unflagged mask."""
        rows = start + np.arange(t.size)
        run = np.searchsorted(self.bounds, rows, side="right") - 1
        k = np.floor((t - self.run_t0[run] + self.slack) / self.w).astype(np.int64)
        new = np.r_[True, (run[1:] != run[:-1]) | (k[1:] != k[:-1])]
        gid = np.cumsum(new) - 1
        continues = self.open_key == (int(run[0]), int(k[0]))
        v = np.column_stack([np.asarray(values[nm], float) for nm in self.names])
        ng = int(gid[-1]) + 1
        cnt = np.bincount(gid[use], minlength=ng).astype(float)
        sums = np.column_stack([np.bincount(gid[use], weights=v[use, j], minlength=ng)
                                for j in range(v.shape[1])])
        self.total += sums.sum(axis=0)
        self.n_used += int(use.sum())
        if continues:                              # the open block goes on as group 0
            sums[0] += self.open_sum
            cnt[0] += self.open_cnt
        elif self.open_key is not None:            # it ended before this chunk
            self._finish(self.open_sum[None, :], np.array([self.open_cnt]))
        self._finish(sums[:-1], cnt[:-1])          # every group but the last is complete
        self.open_key = (int(run[-1]), int(k[-1]))
        self.open_sum, self.open_cnt = sums[-1].copy(), cnt[-1]

    def rms(self) -> dict[str, float]:
        """RMS of the block means per series, and of ``after`` about its overall mean."""
        if self.open_key is not None:
            self._finish(self.open_sum[None, :], np.array([self.open_cnt]))
            self.open_key = None
        n = max(self.n_blocks, 1)
        out = {nm: float(np.sqrt(self.sq[j] / n)) for j, nm in enumerate(self.names)}
        if "after" in self.names:
            j = self.names.index("after")
            c = self.total[j] / max(self.n_used, 1)
            # mean_b (m_b - c)^2 = mean_b m_b^2 - 2 c mean_b m_b + c^2
            out["after_about_mean"] = float(np.sqrt(max(
                (self.sq[j] - 2 * c * self.lin[j]) / n + c * c, 0.0)))
        return out
