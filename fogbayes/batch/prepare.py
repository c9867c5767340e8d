"""Per-sample covariates, fit blocks and thermal segments of many sensors at once.

The single-recording workflow (:mod:`fogbayes.workflow._thermal_data`) computes, per
recording, the covariates z (T, dT/dt by a Savitzky-Golay slope, ...), the block means the
fit uses, and the soak/ramp segments of the metrics. Sensors of one rig share a clock, so
for each group of recordings with identical time stamps this module does each step once for
the whole group:

* dT/dt: one 2-D filter call (:func:`fogbayes.preprocess.temperature_rate` accepts
  (sensors, n) temperatures);
* block means (``average_s`` blocks, with or without Pauta-flagged samples left out): the
  block layout is built once (:func:`fogbayes.preprocess.blocks.block_index`) and every
  column of every sensor is summed by one reduction (:func:`.metrics.block_sums`);
* segments: :func:`fogbayes.preprocess.segments.segment_thermal_rows` (one filter call).

The results equal the per-recording functions' to rounding (sums in another order). Paper
mode (1 s / 10 s smoothing with held differences) and recordings alone on their clock go
through the per-recording functions.
"""

from __future__ import annotations

import numpy as np

from ..errors import FogbayesError
from ..models.thermal import temperature_rate_of, thermal_covariates
from ..preprocess.blocks import block_index
from ..preprocess.segments import segment_thermal_rows
from ..workflow._thermal_data import Blocks, fit_blocks, sample_covariates
from ..workflow.thermal import thermal_segments
from .metrics import block_means, block_sums


def clock_groups(recs) -> list[list[int]]:
    """Indices of recordings grouped by identical time stamps (first-seen order)."""
    groups: dict[bytes, list[int]] = {}
    for i, r in enumerate(recs):
        groups.setdefault(np.ascontiguousarray(r.time).tobytes(), []).append(i)
    return list(groups.values())


def _channel_index(rec, name: str) -> int | None:
    names = list(rec.temperature_names)
    if not names or (name and name not in names):
        return None  # the per-recording path raises the proper error
    return 0 if name == "" else names.index(name)


def covariates(recs, spec, proc) -> list[np.ndarray]:
    """``sample_covariates`` of every recording (rates per clock group in one call).

    A recording whose data the per-recording function rejects raises the same error.
    """
    out: list[np.ndarray | None] = [None] * len(recs)
    for group in clock_groups(recs):
        idx = [_channel_index(recs[i], spec.temperature) for i in group]
        rates = None
        if spec.rate_order > 0 and len(group) > 1 and None not in idx:
            T = np.stack([recs[i].temperatures[:, k] for i, k in zip(group, idx)])
            rates = temperature_rate_of(recs[group[0]].time, T, method=proc.rate_method,
                                        window_s=proc.rate_window_s,
                                        gap_factor=proc.rate_gap_factor)
        for j, i in enumerate(group):
            rec = recs[i]
            out[i] = (sample_covariates(rec, spec, proc) if rates is None else
                      thermal_covariates(rec.time, rec.temperatures, rec.temperature_names, spec,
                                         rate_method=proc.rate_method,
                                         rate_window_s=proc.rate_window_s,
                                         rate_gap_factor=proc.rate_gap_factor,
                                         source=rec.meta.source, rate=rates[j]))
    return out


def blocks(recs, rates, zs, spec, proc, masks=None) -> list[Blocks]:
    """``fit_blocks(rec, rate, z, spec, proc, mask)`` of every recording.

    ``masks``: per recording, None or bool (n,) True for samples left out of the means
    (Pauta-flagged); a block whose samples are all left out is dropped, as there.
    """
    masks = [None] * len(recs) if masks is None else masks
    out: list[Blocks | None] = [None] * len(recs)
    for group in clock_groups(recs):
        if proc.mode == "paper" or len(group) == 1:
            for i in group:
                out[i] = fit_blocks(recs[i], rates[i], zs[i], spec, proc, masks[i])
            continue
        t = recs[group[0]].time
        bi = block_index(t, proc.average_s, partial="drop")
        c = zs[group[0]].shape[1]
        cols = np.stack([np.column_stack([rates[i], zs[i]]).T for i in group])  # (S, c+1, n)
        use = np.stack([np.ones(t.size, bool) if masks[i] is None else ~np.asarray(masks[i])
                        for i in group])
        tm, means, cnt = _masked_block_means(t, cols, use, bi.start, bi.stop)
        for j, i in enumerate(group):
            keep = cnt[j] > 0
            if keep.all():
                out[i] = Blocks(tm[j], means[j, 0], means[j][1:].T, cnt[j])
            else:  # z as (blocks, c) in column order: per-column min/max stay contiguous
                out[i] = Blocks(tm[j, keep], means[j, 0, keep],
                                np.ascontiguousarray(means[j][1:, keep]).T, cnt[j, keep])
    return out


def _masked_block_means(t, x, use, start, stop):
    """Per sensor: mean time of the used samples (of all, where none is used), means of the
    used samples of each column, and their count (``preprocess.blocks.group_mean``).

    t (n,), x (S, k, n), use (S, n) bool; blocks are the ranges [start_j, stop_j).
    """
    S, k, n = x.shape
    length = stop - start
    # each block sample's offset from the block's first time stamp (Unix times lose nothing
    # to rounding once it is subtracted); samples outside the blocks get 0
    pos = np.repeat(start, length) + (np.arange(length.sum())
                                      - np.repeat(np.cumsum(length) - length, length))
    rel = np.zeros(n)
    rel[pos] = t[pos] - np.repeat(t[start], length)
    if use.all():  # nothing left out: plain block means
        sums = block_sums(x.reshape(S * k, n), start, stop).reshape(S, k, -1)
        tm = t[start] + block_means(rel[None, :], start, stop)[0]
        cnt = np.broadcast_to(length, (S, length.size))
        return np.broadcast_to(tm, (S, tm.size)), sums / length, cnt
    w = use.astype(float)
    cnt = np.rint(block_sums(w, start, stop)).astype(np.int64)
    with np.errstate(invalid="ignore", divide="ignore"):
        used_dt = block_sums(w * rel, start, stop)
        all_dt = block_means(rel[None, :], start, stop)[0]
        tm = t[start] + np.where(cnt > 0, used_dt / cnt, all_dt)
        sums = block_sums((x * w[:, None, :]).reshape(S * k, n), start, stop).reshape(S, k, -1)
        means = np.where(cnt[:, None, :] > 0, sums / cnt[:, None, :], np.nan)
    return tm, means, cnt


def segments(recs, zs) -> list[list]:
    """``thermal_segments(rec, z)`` of every recording (one filter call per clock group)."""
    out: list[list | None] = [None] * len(recs)
    for group in clock_groups(recs):
        try:
            rows = segment_thermal_rows(recs[group[0]].time, np.stack([zs[i][:, 0] for i in group]))
        except FogbayesError:  # too short or irregular: each as the workflow does (maybe [])
            rows = [thermal_segments(recs[i], zs[i]) for i in group]
        for i, r in zip(group, rows):
            out[i] = r
    return out
