"""Block sums of a record read in chunks: the grid of :func:`fogbayes.preprocess.blocks.block_index`.

Each run between gaps is cut into ``window_s`` blocks, k = floor((t - t_run + slack) / window_s),
slack = max(1e-3 median step, 16 ulp of max |t|). :meth:`BlockSums.add` returns the blocks a
chunk finished, :meth:`BlockSums.close` the last; O(1) memory. Complete (``partial="drop"``):
t_run + (k + 1) window_s <= t_last + dt + slack.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .scan import TimeScan


class Finished(NamedTuple):
    """Blocks finished by one call: run, position ``k``, sums (g, m) and counts (g,)."""

    run: np.ndarray
    k: np.ndarray
    sums: np.ndarray
    count: np.ndarray


class BlockSums:
    """Sums of ``m`` series over the ``window_s`` blocks of the record of ``scan``."""

    def __init__(self, scan: TimeScan, window_s: float, n_series: int):
        self.w = float(window_s)
        self.slack = max(1e-3 * scan.dt_median, 16 * float(np.spacing(scan.t_absmax)))
        self.bounds, self.run_t0 = scan.bounds, scan.run_t0
        self.run_end = scan.run_t_last + scan.dt_median   # a run covers [first, last + dt)
        self.open_key: tuple[int, int] | None = None        # (run, k) of the block still open
        self.open_sum = np.zeros(n_series)
        self.open_cnt = 0.0

    def complete(self, done: Finished) -> np.ndarray:
        """Which of ``done``'s blocks cover their whole window."""
        end = self.run_t0[done.run] + (done.k + 1) * self.w
        return end <= self.run_end[done.run] + self.slack

    def add(self, start: int, t: np.ndarray, values: np.ndarray, use: np.ndarray) -> Finished:
        """Rows ``start ..`` of the record: times, values (n, m), the samples to sum."""
        rows = start + np.arange(t.size)
        run = np.searchsorted(self.bounds, rows, side="right") - 1
        k = np.floor((t - self.run_t0[run] + self.slack) / self.w).astype(np.int64)
        new = np.r_[True, (run[1:] != run[:-1]) | (k[1:] != k[:-1])]
        gid = np.cumsum(new) - 1
        first = np.flatnonzero(new)
        ng = first.size
        cnt = np.bincount(gid[use], minlength=ng).astype(float)
        sums = np.column_stack([np.bincount(gid[use], weights=values[use, j], minlength=ng)
                                for j in range(values.shape[1])])
        g_run, g_k = run[first], k[first]
        if self.open_key == (int(g_run[0]), int(g_k[0])):  # the open block goes on as group 0
            sums[0] += self.open_sum
            cnt[0] += self.open_cnt
            done = Finished(g_run[:-1], g_k[:-1], sums[:-1], cnt[:-1])
        elif self.open_key is not None:                     # it ended before this chunk
            r, kk = self.open_key
            done = Finished(np.r_[r, g_run[:-1]], np.r_[kk, g_k[:-1]],
                            np.vstack([self.open_sum, sums[:-1]]), np.r_[self.open_cnt, cnt[:-1]])
        else:
            done = Finished(g_run[:-1], g_k[:-1], sums[:-1], cnt[:-1])
        self.open_key = (int(g_run[-1]), int(g_k[-1]))
        self.open_sum, self.open_cnt = sums[-1].copy(), float(cnt[-1])
        return done

    def close(self) -> Finished:
        """The block still open (none after the first call)."""
        if self.open_key is None:
            m = self.open_sum.size
            return Finished(np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros((0, m)),
                            np.zeros(0))
        r, k = self.open_key
        self.open_key = None
        return Finished(np.array([r]), np.array([k]), self.open_sum[None, :],
                        np.array([self.open_cnt]))
