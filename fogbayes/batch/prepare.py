"""Per-sample covariates, fit blocks and thermal segments of many sensors at once.

Per group of recordings with identical time stamps, the steps of :mod:`fogbayes.thermal.data`
once: dT/dt (:func:`fogbayes.preprocess.temperature_rate` on (sensors, n)), block means
(:func:`fogbayes.preprocess.blocks.block_index`, :func:`.block_kernels.masked_block_means`),
segments (:func:`fogbayes.preprocess.segments.segment_thermal_rows`). Paper mode and lone
clocks use the per-recording functions.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..errors import FogbayesError
from ..thermal.model import temperature_rate_of, thermal_covariates
from ..preprocess.blocks import block_index
from ..preprocess.segments import segment_thermal_rows
from ..thermal.data import Blocks, fit_blocks, sample_covariates
from ..thermal.workflow import thermal_segments
from . import block_kernels


def clock_groups(recs) -> list[list[int]]:
    """Indices of recordings grouped by identical time stamps (first-seen order)."""
    groups: dict[bytes, list[int]] = {}
    for i, r in enumerate(recs):
        groups.setdefault(np.ascontiguousarray(r.time).tobytes(), []).append(i)
    return list(groups.values())


def covariate_major(zs) -> np.ndarray:
    """Per-sample covariates of S sensors, (n, c) each, as one C-contiguous (S, c, n) array
    (each covariate of a sensor one contiguous row: the layout the compiled kernels read)."""
    out = np.empty((len(zs), zs[0].shape[1], zs[0].shape[0]))
    for s, z in enumerate(zs):
        out[s] = z.T
    return out


def _channel_index(rec, name: str) -> int | None:
    names = list(rec.temperature_names)
    if not names or (name and name not in names):
        return None  # the per-recording path raises the proper error
    return 0 if name == "" else names.index(name)


def covariates(recs, spec, proc, groups=None) -> np.ndarray:
    """``sample_covariates`` of every recording (same length), covariate-major (S, c, n);
    dT/dt per clock group in one call. ``groups``: :func:`clock_groups` of ``recs`` when
    already known.

    A recording whose data the per-recording function rejects raises the same error.
    """
    out = None
    for group in clock_groups(recs) if groups is None else groups:
        idx = [_channel_index(recs[i], spec.temperature) for i in group]
        if spec.rate_order > 0 and len(group) > 1 and None not in idx:
            T = np.stack([recs[i].temperatures[:, k] for i, k in zip(group, idx)])
            rates = temperature_rate_of(recs[group[0]].time, T, method=proc.rate_method,
                                        window_s=proc.rate_window_s,
                                        gap_factor=proc.rate_gap_factor)
            if not spec.extra and not spec.gradient:  # (T, dT/dt): thermal_covariates' columns
                out = _into(out, len(recs), group, np.stack([T, rates], axis=1))
                continue
            zs = [thermal_covariates(recs[i].time, recs[i].temperatures,
                                     recs[i].temperature_names, spec,
                                     rate_method=proc.rate_method,
                                     rate_window_s=proc.rate_window_s,
                                     rate_gap_factor=proc.rate_gap_factor,
                                     source=recs[i].meta.source, rate=rates[j])
                  for j, i in enumerate(group)]
        else:
            zs = [sample_covariates(recs[i], spec, proc) for i in group]
        out = _into(out, len(recs), group, covariate_major(zs))
    return out


def _into(out, S: int, rows, values: np.ndarray) -> np.ndarray:
    """``out[rows] = values``, allocating out (S, c, n) on first use; all rows: no copy."""
    if out is None and len(rows) == S and list(rows) == list(range(S)):
        return values
    if out is None:
        out = np.empty((S,) + values.shape[1:])
    out[rows] = values
    return out


class BlockArrays(NamedTuple):
    """Fit blocks of S recordings stacked: time, y (S, m), z (S, c, m), count (S, m).

    A block with count 0 (all its samples flagged, or padding after a shorter recording)
    is not a block of that recording (``fit_blocks`` drops it) and its values mean nothing
    (NaN, or the left-out sample itself). Weighted by its count it adds nothing to a fit,
    so the stacked fit equals the one without it; read the blocks through :meth:`of`, or
    with ``count > 0``.
    """

    time: np.ndarray
    y: np.ndarray
    z: np.ndarray
    count: np.ndarray

    def of(self, s: int) -> Blocks:
        """Recording s's ``Blocks``, as ``fit_blocks`` returns them."""
        keep = self.count[s] > 0
        return Blocks(self.time[s, keep], self.y[s, keep],
                      np.ascontiguousarray(self.z[s][:, keep]).T, self.count[s, keep])


def block_arrays(recs, rates, Z, spec, proc, use=None, groups=None) -> BlockArrays:
    """Stacked ``fit_blocks(rec, rate, z, spec, proc, ~use)`` of every recording.

    ``rates`` (S, n) deg/h, ``Z`` (S, c, n) covariates (:func:`covariate_major`), ``use``
    (S, n) bool, False for samples left out of the means (Pauta-flagged; default: all used).
    """
    S, n = rates.shape
    use = np.ones((S, n), bool) if use is None else np.asarray(use, bool)
    parts = []
    for group in clock_groups(recs) if groups is None else groups:
        if proc.mode == "paper" or len(group) == 1:
            for i in group:
                b = fit_blocks(recs[i], rates[i], Z[i].T, spec, proc, ~use[i])
                parts.append(([i], b.time[None], b.y[None], b.z.T[None], b.count[None]))
            continue
        g = np.asarray(group)
        t = recs[group[0]].time
        bi = block_index(t, proc.average_s, partial="drop")
        whole = g.size == S  # one clock for all (groups are in first-seen order): no copies
        y, z, u = (rates, Z, use) if whole else (rates[g], Z[g], use[g])
        if np.all(bi.stop - bi.start == 1):  # blocks of one sample are the samples themselves
            rows = bi.start
            if np.all(np.diff(rows) == 1):  # consecutive samples: views, not copies
                rows = slice(int(rows[0]), int(rows[-1]) + 1)
            tm = np.broadcast_to(t[rows], (g.size, bi.start.size))
            ym, zm, cnt = y[:, rows], z[:, :, rows], u[:, rows].astype(np.int64)
        else:
            tm, ym, zm, cnt = block_kernels.masked_block_means(t, y, z, u, bi.start, bi.stop)
        parts.append((group, tm, ym, zm, cnt))
    if len(parts) == 1 and parts[0][0] == list(range(S)):
        return BlockArrays(*parts[0][1:])
    m = max(p[2].shape[1] for p in parts)
    c = Z.shape[1]
    out = BlockArrays(np.full((S, m), np.nan), np.full((S, m), np.nan),
                      np.full((S, c, m), np.nan), np.zeros((S, m), np.int64))
    for idx, tm, ym, zm, cnt in parts:
        k = tm.shape[1]
        out.time[idx, :k], out.y[idx, :k], out.z[idx, :, :k], out.count[idx, :k] = tm, ym, zm, cnt
    return out


def stack_blocks(blocks: list[Blocks]) -> BlockArrays:
    """``Blocks`` of several recordings as :class:`BlockArrays` (padded with count-0 blocks)."""
    m = max(b.y.size for b in blocks)
    S, c = len(blocks), blocks[0].z.shape[1]
    out = BlockArrays(np.full((S, m), np.nan), np.full((S, m), np.nan),
                      np.full((S, c, m), np.nan), np.zeros((S, m), np.int64))
    for s, b in enumerate(blocks):
        k = b.y.size
        out.time[s, :k], out.y[s, :k], out.z[s, :, :k], out.count[s, :k] = b.time, b.y, b.z.T, b.count
    return out


def blocks(recs, rates, zs, spec, proc, masks=None) -> list[Blocks]:
    """``fit_blocks(rec, rate, z, spec, proc, mask)`` of every recording.

    ``masks``: per recording, None or bool (n,) True for samples left out of the means
    (Pauta-flagged); a block whose samples are all left out is dropped, as there.
    """
    rates = np.stack(rates)
    use = None if masks is None else np.stack(
        [np.ones(rates.shape[1], bool) if m is None else ~np.asarray(m, bool) for m in masks])
    arrays = block_arrays(recs, rates, covariate_major(zs), spec, proc, use)
    return [arrays.of(s) for s in range(len(recs))]


def segments(recs, temperatures, groups=None) -> list[list]:
    """``thermal_segments(rec, z)`` of every recording, from the fit's temperature
    covariate ``z[:, 0]`` of each (``temperatures``: (S, n) or one (n,) per recording); one
    filter call per clock group."""
    out: list[list | None] = [None] * len(recs)
    for group in clock_groups(recs) if groups is None else groups:
        try:
            rows = segment_thermal_rows(recs[group[0]].time,
                                        np.stack([temperatures[i] for i in group]))
        except FogbayesError:  # too short or irregular: each as the workflow does (maybe [])
            rows = [thermal_segments(recs[i], np.asarray(temperatures[i])[:, None])
                    for i in group]
        for i, r in zip(group, rows):
            out[i] = r
    return out
