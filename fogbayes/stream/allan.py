"""Overlapping Allan deviation of a record larger than memory, in one streaming pass.

:func:`stream_allan` reads the output in chunks (:mod:`.sources`), converts it to ``unit``,
places it on the sample grid and feeds :mod:`fogbayes.stats.allan_accumulators`: the numbers of
:func:`fogbayes.stats.allan.allan_deviation` (``oadev``) to rounding. Memory O(max_lag + chunk)
(``StreamAllan.memory_bytes``); cluster sizes above ``max_lag`` are listed in ``skipped``.
``grid="time"``: sample i at k_i = rint((t_i - t_0) fs) within ``tolerance``, missing points NaN
(as :func:`fogbayes.allan.workflow.uniform_rate`; median step from :mod:`.scan`);
``grid="index"``: rows are consecutive samples.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..errors import FogbayesError, TooShortError
from ..stats.taus import cluster_sizes
from ..data.units import convert_rate
from ..stats.allan_accumulators import variance
from ..stats.allan_blocked import accumulator
from .scan import scan_time
from .sources import DEFAULT_ROWS, RecordSource, open_source

DEFAULT_MAX_LAG = 1 << 22


class StreamAllan(NamedTuple):
    """Overlapping Allan deviation of a streamed record (arrays of length len(tau))."""

    tau: np.ndarray       # s
    m: np.ndarray         # cluster sizes (samples)
    var: np.ndarray       # unit^2
    dev: np.ndarray       # unit
    n_terms: np.ndarray   # terms kept (gaps excluded)
    fs: float
    n: int                # samples on the grid (missing ones included)
    n_missing: int
    unit: str
    skipped: tuple        # cluster sizes above max_lag, not computed
    memory_bytes: int     # the accumulator's buffers


class GridError(FogbayesError):
    """Time stamps off the uniform grid, or gaps that make the grid huge."""


def _grid_length(source, fs, rows, tolerance):
    """(t0, samples on the grid) from a pass over the time column."""
    t0 = t_last = None
    for ch in source.chunks(rows, fields=("time",)):
        t0 = float(ch.time[0]) if t0 is None else t0
        t_last = float(ch.time[-1])
    return t0, int(np.rint((t_last - t0) * fs)) + 1


def _placed(source, fs, t0, rows, unit, tolerance, n_grid):
    """Rate pieces on the uniform grid (NaN in the missing places), in order."""
    k_next = 0
    for ch in source.chunks(rows, fields=("time", "output")):
        y = np.asarray(convert_rate(ch.output, source.unit, unit,
                                    scale_factor=source.scale_factor), dtype=float)
        pos = (ch.time - t0) * fs
        k = np.rint(pos).astype(np.int64)
        bad = np.flatnonzero((np.abs(pos - k) > tolerance)
                             | (np.diff(k, prepend=k_next - 1) < 1))
        if bad.size:
            r = ch.start + int(bad[0])
            raise GridError(f"time stamps are not on a uniform {1 / fs:g} s grid (first "
                            f"off-grid row: t = {ch.time[bad[0]]!r})", file=source.source,
                            column=source.time_name, row=r,
                            fix="resample to a constant rate first (missing samples are fine)")
        if k[-1] - k[0] + 1 == k.size and k[0] == k_next:
            yield y  # no gap in this chunk: the usual case
        else:
            jumps = np.flatnonzero(np.diff(k, prepend=k_next - 1) > 1)
            a = 0
            for j in list(jumps) + [k.size]:
                if j > a:
                    yield y[a:j]
                if j < k.size:
                    gap = int(k[j] - (k[j - 1] if j else k_next - 1) - 1)
                    for g in range(0, gap, rows):
                        yield np.full(min(rows, gap - g), np.nan)
                a = j
        k_next = int(k[-1]) + 1


def stream_allan(source, *, fs: float | None = None, taus="octave", per_decade: int = 20,
                 m_max: int | None = None, max_lag: int = DEFAULT_MAX_LAG,
                 unit: str | None = "deg/h", grid: str = "auto", tolerance: float = 0.05,
                 rows: int = DEFAULT_ROWS, chunk: int | None = None) -> StreamAllan:
    """Overlapping ADEV of ``source`` (a :class:`RecordSource` or a path) in bounded memory.

    Args:
        fs: sample rate (Hz); default the file's metadata, else 1 / exact median step.
        taus, per_decade, m_max: the grid of :func:`fogbayes.stats.taus.cluster_sizes`, or
            explicit cluster sizes.
        max_lag: largest cluster size computed (memory budget, see the module doc).
        unit: rate unit of the result (None = the file's unit, no conversion).
        grid: ``"time"`` (place samples by their time stamps), ``"index"`` (rows are
            consecutive samples) or ``"auto"`` (time if the file has a time column).
        rows: rows read per chunk; chunk: samples per accumulator step (default: the
            accumulator's own, see :func:`fogbayes.stats.allan_blocked.accumulator`).
    """
    if not isinstance(source, RecordSource):
        source = open_source(source)
    if grid == "auto":
        grid = "time" if source.time_name in source.columns else "index"
    if grid not in ("time", "index"):
        raise FogbayesError(f"unknown grid {grid!r}", column="grid",
                            fix="use 'time' (time stamps) or 'index' (rows are consecutive)")
    unit = unit or source.unit
    if fs is None:
        fs = source.sample_rate or (scan_time(source, rows=rows).sample_rate
                                    if source.time_name in source.columns else None)
    if fs is None or not (np.isfinite(fs) and fs > 0):
        raise FogbayesError(f"no usable sample rate ({fs!r})", file=source.source,
                            column="sample_rate", fix="pass fs (Hz) or add a time column")
    fs = float(fs)
    if grid == "time":
        source.require("time")
        t0, n_grid = _grid_length(source, fs, rows, tolerance)
        if n_grid > 20 * source.n:
            raise GridError(f"gaps make the record {n_grid / source.n:.0f} x longer than its "
                            f"{source.n} samples", file=source.source, column=source.time_name,
                            fix="analyse the continuous segments separately")
    else:
        n_grid = source.n
    if n_grid < 3:
        raise TooShortError(f"the Allan deviation needs at least 3 samples, got {n_grid}",
                            file=source.source, fix="record longer")
    if isinstance(taus, str):
        ms = cluster_sizes(n_grid, taus, per_decade=per_decade, m_max=m_max, kind="oadev")
    else:
        ms = tuple(int(m) for m in np.unique(np.asarray(taus, dtype=np.int64)))
        if not ms or ms[0] < 1 or 2 * ms[-1] > n_grid:
            raise TooShortError(f"cluster sizes must lie in 1..{n_grid // 2} for {n_grid} "
                                "samples", column="taus", fix="pass smaller cluster sizes")
    skipped = tuple(m for m in ms if m > max_lag)
    ms = tuple(m for m in ms if m <= max_lag)
    if not ms:
        raise FogbayesError(f"every cluster size exceeds max_lag={max_lag}", column="max_lag",
                            fix="raise max_lag or ask for shorter taus")
    acc, ms, pick = accumulator(ms, chunk=chunk)
    n_missing = 0
    if grid == "time":
        pieces = _placed(source, fs, t0, rows, unit, tolerance, n_grid)
    else:
        pieces = (np.asarray(convert_rate(ch.output, source.unit, unit,
                                          scale_factor=source.scale_factor), dtype=float)
                  for ch in source.chunks(rows, fields=("output",), allow_nan=("output",)))
    for y in pieces:
        n_missing += int(np.isnan(y).sum())
        acc.update(y)
    sums, counts = pick(*acc.result())
    var = variance(ms, sums, counts)
    return StreamAllan(np.asarray(ms) / fs, np.asarray(ms), var, np.sqrt(var), counts, fs,
                       int(acc.n), n_missing, unit, skipped, int(acc.nbytes))
