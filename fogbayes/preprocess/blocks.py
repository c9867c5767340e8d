"""Block averaging over a time window, cut at gaps.

Per run between gaps (step > ``gap_factor`` median steps): k_i = floor((t_i - t_0 + eps) / W),
eps = max(1e-3 dt, 16 ulp(t)); block value and time stamp are the means of its samples.
Complete when t_0 + (k+1) W <= t_last + dt; ``partial="drop"`` (default) drops each run's
incomplete last block, ``"keep"`` keeps it. Grids of two windows start at the same samples.
"""

from __future__ import annotations

import dataclasses
from typing import NamedTuple

import numpy as np

from ..errors import ArgumentError, ShapeError, TooShortError
from ._checks import GAP_FACTOR, as_1d, check_time, check_window, median_step, segment_bounds


class BlockIndex(NamedTuple):
    """Which block each sample is in.

    block: int (n,), block number of each sample, -1 for samples of dropped blocks.
    start, stop: (B,) first and one-past-last sample of each block.
    complete: bool (B,), the block covers its whole window.
    segment: (B,) run (between gaps) the block lies in.
    k: (B,) position of the block on its run's grid (0 at the run's first sample).
    """

    block: np.ndarray
    start: np.ndarray
    stop: np.ndarray
    complete: np.ndarray
    segment: np.ndarray
    k: np.ndarray


class BlockAverage(NamedTuple):
    """Block means of arrays.

    time: (B,) mean time stamp of the samples averaged (of all the block's samples when
        every one of them is masked).
    mean: (B,) or (B, k) block means; NaN where every sample of the block is masked.
    count: (B,) samples averaged.
    start, stop: (B,) sample range of each block in the input.
    """

    time: np.ndarray
    mean: np.ndarray
    count: np.ndarray
    start: np.ndarray
    stop: np.ndarray


class BlockedRecording(NamedTuple):
    """A block-averaged Recording and, per output row, the samples behind it."""

    recording: object  # fogbayes.data.Recording
    count: np.ndarray
    start: np.ndarray
    stop: np.ndarray


def sample_grid(t: np.ndarray, window_s: float, gap_factor: float = GAP_FACTOR):
    """Per sample: run number and block position ``k`` on the run's grid; and the run bounds."""
    bounds = segment_bounds(t, gap_factor)
    seg = np.repeat(np.arange(bounds.size - 1), np.diff(bounds))
    t0 = t[bounds[:-1]][seg]
    k = np.floor((t - t0 + time_slack(t)) / window_s).astype(np.int64)
    return seg, k, bounds


def time_slack(t: np.ndarray) -> float:
    """Tolerance (s) for a time stamp on a block edge: 1e-3 of a step, or 16 ulp of the
    largest stamp (Unix times ~1.7e9 s carry ~2e-7 s of rounding)."""
    return max(1e-3 * median_step(t), 16 * float(np.spacing(np.max(np.abs(t)))))


def group_starts(*keys: np.ndarray) -> np.ndarray:
    """Group number of each sample: a new group wherever any key changes (keys are sorted)."""
    new = np.zeros(keys[0].size, bool)
    new[0] = True
    for key in keys:
        new[1:] |= key[1:] != key[:-1]
    return np.cumsum(new) - 1


def block_index(time, window_s: float, *, partial: str = "drop",
                gap_factor: float = GAP_FACTOR) -> BlockIndex:
    """Assign samples to blocks of ``window_s`` seconds, cut at gaps (see module doc)."""
    if partial not in ("drop", "keep"):
        raise ArgumentError(f"partial must be 'drop' or 'keep', got {partial!r}", column="partial",
                            fix="pass partial='drop' (complete blocks only) or 'keep'")
    t = check_time(time)
    w = check_window(window_s, t)
    seg, k, bounds = sample_grid(t, w, gap_factor)
    gid = group_starts(seg, k)
    start = np.flatnonzero(np.r_[True, gid[1:] != gid[:-1]])
    stop = np.r_[start[1:], t.size]
    bseg, bk = seg[start], k[start]
    run_t0 = t[bounds[:-1]]
    run_end = t[bounds[1:] - 1] + median_step(t)  # a run covers [first, last + dt)
    block_end = run_t0[bseg] + (bk + 1) * w
    complete = block_end <= run_end[bseg] + time_slack(t)
    if partial == "drop":
        if not complete.any():
            raise TooShortError(f"no run between gaps is as long as window_s={w:g} s",
                                column="window_s",
                                fix="use a shorter window or partial='keep'")
        renumber = np.where(complete, np.cumsum(complete) - 1, -1)
        gid = renumber[gid]
        start, stop, bseg, bk = start[complete], stop[complete], bseg[complete], bk[complete]
        complete = complete[complete]
    return BlockIndex(gid, start, stop, complete, bseg, bk)


def group_mean(gid: np.ndarray, n_groups: int, t: np.ndarray, values: np.ndarray,
               use: np.ndarray | None = None):
    """Mean time, mean values (columns of a 2-D ``values``) and count per group id >= 0."""
    ok = gid >= 0 if use is None else (gid >= 0) & use
    cnt = np.bincount(gid[ok], minlength=n_groups)
    # Subtract each group's first time before summing: Unix-time stamps (~1.7e9 s) would
    # otherwise lose ~1e-7 s to rounding in the sums.
    valid = gid >= 0
    head = np.flatnonzero(valid & np.r_[True, gid[1:] != gid[:-1]])  # groups are contiguous
    first = np.zeros(n_groups)
    first[gid[head]] = t[head]
    all_cnt = np.bincount(gid[valid], minlength=n_groups)
    all_dt = np.bincount(gid[valid], weights=t[valid] - first[gid[valid]], minlength=n_groups)
    used_dt = np.bincount(gid[ok], weights=t[ok] - first[gid[ok]], minlength=n_groups)
    has = cnt > 0
    rel = np.divide(used_dt, cnt, out=np.zeros(n_groups), where=has)
    rel_all = np.divide(all_dt, all_cnt, out=np.zeros(n_groups), where=all_cnt > 0)
    tm = first + np.where(has, rel, rel_all)
    means = np.full((n_groups, values.shape[1]), np.nan)
    for j in range(values.shape[1]):
        s = np.bincount(gid[ok], weights=values[ok, j], minlength=n_groups)
        np.divide(s, cnt, out=means[:, j], where=has)
    return tm, means, cnt


def _as_columns(values, n: int) -> tuple[np.ndarray, bool]:
    v = np.asarray(values, dtype=float)
    if v.ndim not in (1, 2) or v.shape[0] != n:
        raise ShapeError(f"values have shape {v.shape} but time has {n} samples", column="values",
                         fix="pass values of shape (n,) or (n, k), one row per time stamp")
    if v.ndim == 2:
        as_1d(v.ravel(), "values")  # finiteness check
        return v, False
    return as_1d(v, "values")[:, None], True


def _mask(mask, n: int) -> np.ndarray | None:
    if mask is None:
        return None
    m = np.asarray(mask, dtype=bool)
    if m.shape != (n,):
        raise ShapeError(f"mask has shape {m.shape}, expected ({n},)", column="mask",
                         fix="pass one boolean flag per sample (e.g. OutlierFlags.mask)")
    return ~m


def block_average(data, window_s: float, *, time=None, partial: str = "drop", mask=None,
                  gap_factor: float = GAP_FACTOR):
    """Average a Recording, or arrays, over blocks of ``window_s`` seconds.

    Args:
        data: a :class:`fogbayes.data.Recording`, or values of shape (n,) or (n, k) with
            ``time`` given.
        window_s: block length (s), at least one sample interval, at most the record.
        time: time stamps (s) of array ``data``.
        partial: "drop" the incomplete last block of each run between gaps, or "keep" it.
        mask: optional bool (n,), True for samples to leave out of the means (flagged
            outliers, e.g. ``OutlierFlags.mask``). They stay counted in ``start:stop``.
        gap_factor: a step longer than this many median steps is a gap.

    Returns:
        For arrays, :class:`BlockAverage`. For a Recording, :class:`BlockedRecording`:
        every column (output, temperatures, input_rate) averaged over the same unmasked
        samples, time stamps = their mean, ``meta.sample_rate = 1 / window_s``; blocks
        whose samples are all masked are left out (a Recording holds no NaN).

    Example:
        >>> import numpy as np
        >>> b = block_average(np.arange(6.0), 2.0, time=np.arange(6.0))
        >>> b.time.tolist(), b.mean.tolist(), b.count.tolist()
        ([0.5, 2.5, 4.5], [0.5, 2.5, 4.5], [2, 2, 2])
    """
    from ..data import Recording

    if isinstance(data, Recording):
        return _average_recording(data, window_s, partial, mask, gap_factor)
    if time is None:
        raise ShapeError("arrays need their time stamps", column="time",
                         fix="pass time=... (s), or a Recording")
    t = check_time(time)
    v, flat = _as_columns(data, t.size)
    bi = block_index(t, window_s, partial=partial, gap_factor=gap_factor)
    tm, means, cnt = group_mean(bi.block, bi.start.size, t, v, _mask(mask, t.size))
    return BlockAverage(tm, means[:, 0] if flat else means, cnt, bi.start, bi.stop)


def _average_recording(rec, window_s, partial, mask, gap_factor) -> BlockedRecording:
    k = rec.temperatures.shape[1]
    cols = [rec.output[:, None], rec.temperatures]
    if rec.input_rate is not None:
        cols.append(rec.input_rate[:, None])
    b = block_average(np.hstack(cols), window_s, time=rec.time, partial=partial, mask=mask,
                      gap_factor=gap_factor)
    keep = b.count > 0
    m = b.mean[keep]
    meta = dataclasses.replace(rec.meta, sample_rate=1.0 / float(window_s),
                               extra={**rec.meta.extra, "block_average_s": float(window_s)})
    out = rec.replace(time=b.time[keep], output=m[:, 0], temperatures=m[:, 1:1 + k],
                      input_rate=m[:, 1 + k] if rec.input_rate is not None else None, meta=meta)
    return BlockedRecording(out, b.count[keep], b.start[keep], b.stop[keep])
