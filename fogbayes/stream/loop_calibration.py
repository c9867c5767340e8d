"""Apply a loop calibration (``fogbayes loop --json``) to a record larger than memory.

The four whole-record inputs of :func:`fogbayes.loop.calibration.apply_calibration`, each built
exactly from chunks: spike flags (:func:`fogbayes.loop.context.spike_flags`, median and MAD
by :mod:`.select`), the block grid, dT/dt (:class:`fogbayes.preprocess.covariates.RateCurve` from
block sums) and filter state carried between chunks
(:meth:`fogbayes.effects.kinds.Kind.chunk_columns`). A writing pass then subtracts the bias
(with :mod:`.block_rms` and :mod:`.stability`) or solves for the rate
(:func:`fogbayes.loop.compensate.solve_rate`).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..preprocess.operating_time import operating_time_chunk
from ..loop.context import MAD_TO_SIGMA, spikes_between
from ..preprocess.covariates import (Covariates, block_index, block_step, grid_of_counts,
                                   rate_curve, rate_window)
from ..effects.terms import chunk_columns
from ..loop.calibration import (RATE_WINDOW_S, TARGET_BLOCKS, RangeCheck, applied_terms)
from ..loop.calibration_doc import channel_order, validate_loop_document
from ..loop.compensate import solve_rate
from ..data.units import convert_rate
from .block_rms import StreamBlockRMS
from .scan import scan_time
from .stability import StreamStability
from .select import stream_median
from .sources import DEFAULT_ROWS, RecordSource, open_source
from .writers import check_sink, open_sink


class LoopStream(NamedTuple):
    """What was written and what the user should know (as the in-memory ``Applied``)."""

    path: object
    n: int
    columns: tuple
    outliers: int
    skipped: list       # run-event terms not applied
    outside: list       # covariates outside the calibrated range
    passes: int         # passes over the input, scans included
    rms_10s: dict | None  # bias family: 10 s RMS before / after / after about its mean
    metrics: dict | None  # bias family: bias and bias stability before/after (paper 004)


def _rates(source: RecordSource, rows: int, fields, unit_of):
    """(chunk, rate in deg/h, first rate of the next chunk or None), one chunk read ahead."""
    prev = None
    for ch in source.chunks(rows, fields=fields):
        rate = unit_of(ch.output)
        if prev is not None:
            yield prev[0], prev[1], float(rate[0])
        prev = (ch, rate)
    if prev is not None:
        yield prev[0], prev[1], None


def _differences(source: RecordSource, rows: int, unit_of):
    """A pass yielding the first differences of the rate, chunk by chunk."""
    last = None
    for ch in source.chunks(rows, fields=("output",)):
        x = unit_of(ch.output)
        d = np.diff(x) if last is None else np.diff(x, prepend=last)
        last = float(x[-1])
        yield d


class _Spikes:
    """The spike flags of :func:`~fogbayes.loop.context.spike_flags`, chunk by chunk."""

    def __init__(self, source: RecordSource, rows: int, unit_of, n_sigma: float = 6.0):
        self.n_sigma, self.on, self.passes = n_sigma, source.n >= 5, 0
        self.med = self.s = 0.0
        if not self.on:
            return
        m = source.n - 1
        self.med, p1 = stream_median(lambda: _differences(source, rows, unit_of), m)
        mad, p2 = stream_median(lambda: (np.abs(d - self.med) for d in
                                         _differences(source, rows, unit_of)), m)
        self.s = MAD_TO_SIGMA * mad  # as spike_scale
        self.on = self.s > 0
        self.passes = p1 + p2

    def flags(self, rate: np.ndarray, prev: float | None,
              nxt: float | None) -> np.ndarray:
        """Flags of the rows of a chunk; ``prev``/``nxt`` the rates just outside it."""
        flag = np.zeros(rate.size, bool)
        if not self.on:
            return flag
        head = [] if prev is None else [prev]
        x = np.concatenate([head, rate, [] if nxt is None else [nxt]])
        inner = np.zeros(x.size, bool)
        inner[1:-1] = spikes_between(np.diff(x), self.med, self.s, self.n_sigma)
        return inner[len(head):len(head) + rate.size]



def _covariates(ch, t0: float, duration: float, order, curve, names, carry):
    """Per-sample covariates of one chunk (as ``covariates_of``) and the operating-time carry."""
    t = ch.time - t0
    T = np.zeros((t.size, 0)) if ch.temperatures is None else ch.temperatures
    T = T if order is None else T[:, order]
    Tdot = curve(t) if curve is not None else None
    op = None
    if ch.input_rate is not None:
        op, carry = operating_time_chunk(t, ch.input_rate, carry)
    return Covariates(t, T, names, Tdot, ch.input_rate, duration, op), carry


def compensate_loop_stream(source, doc: dict, out, *, rows: int = DEFAULT_ROWS,
                           run_events: bool = False, include_time: bool = True,
                           dtype=np.float64) -> LoopStream:
    """Compensate ``source`` (a :class:`RecordSource` or path) with the loop document
    ``doc`` into ``out`` (a folder of ``<column>.npy``, ``.npz`` or ``.parquet``): the same
    columns and numbers as ``fogbayes compensate`` in memory (module doc)."""
    check_sink(out)
    if not isinstance(source, RecordSource):
        source = open_source(source)
    validate_loop_document(doc)
    cal = doc["calibration"]
    composite = cal["family"] == "composite"
    source.require("time", "output")
    order = channel_order(doc, source.temperature_names, source.source)
    names = tuple(doc["input"]["temperatures"]) if order is not None \
        else tuple(source.temperature_names)
    if composite:
        source.require("input_rate")
    terms, beta, skipped = applied_terms(cal, run_events)
    proc = cal.get("processing") or {}

    def unit_of(y):
        return np.asarray(convert_rate(y, source.unit, "deg/h",
                                       scale_factor=source.scale_factor), dtype=float)

    scan = scan_time(source, rows=rows)
    spikes = _Spikes(source, rows, unit_of)
    t0, duration = scan.t_first, scan.t_last - scan.t_first
    fs = source.sample_rate or scan.sample_rate
    dt = block_step(duration, fs, target_blocks=int(proc.get("target_blocks", TARGET_BLOCKS)))
    nb = int(block_index(np.array([duration]), dt, fs)[0]) + 1
    fields = ("time", "output", "temperatures") + (("input_rate",) if composite else ())

    # the block pass: used-sample counts and the block sums of T (first channel) and t
    count, sum_T, sum_t = np.zeros(nb), np.zeros(nb), np.zeros(nb)
    prev = None
    for ch, rate, nxt in _rates(source, rows, ("time", "output", "temperatures"), unit_of):
        use = ~spikes.flags(rate, prev, nxt)
        prev = float(rate[-1])
        t = ch.time - t0
        idx = block_index(t, dt, fs)[use]
        np.add.at(count, idx, 1.0)
        if len(source.temperature_names):
            col = 0 if order is None else order[0]
            np.add.at(sum_T, idx, ch.temperatures[use, col])  # in sample order, as bincount
        np.add.at(sum_t, idx, t[use])
    grid = grid_of_counts(dt, count)
    cnt = np.maximum(count, 1)
    curve = None
    if len(source.temperature_names):
        curve = rate_curve(sum_T / cnt, sum_t / cnt, grid.mask, grid.t, dt,
                           rate_window(grid, float(proc.get("rate_window_s", RATE_WINDOW_S))))

    ranges = RangeCheck(cal.get("valid") or {}, list(names))
    cols = {"time": np.float64} if include_time else {}
    cols.update({"rate" if composite else "output": dtype, "outlier": np.bool_})
    states = carry = prev = None
    rms = None if composite else StreamBlockRMS(scan, ("before", "after"))
    stability = None if composite else StreamStability(scan)
    n_out = 0
    with open_sink(out, source.n, cols) as sink:  # an exception removes the partial output
        for ch, rate, nxt in _rates(source, rows, fields, unit_of):
            flag = spikes.flags(rate, prev, nxt)
            prev = float(rate[-1])
            cov, carry = _covariates(ch, t0, duration, order, curve, names, carry)
            ranges.add(cov)
            part = {}
            if terms:
                X, states = chunk_columns(terms, cov, states)
            if composite:
                w = solve_rate(terms, beta, cov, rate, cols=X)
                flag = flag | ~np.isfinite(w)
                part["rate"] = w
            else:
                bias = np.column_stack(X) @ beta if terms else np.zeros(rate.size)
                rms.add(ch.start, ch.time, {"before": rate, "after": rate - bias}, ~flag)
                stability.add(ch.start, ch.time, rate, rate - bias)
                part["output"] = np.asarray(convert_rate(rate - bias, "deg/h", source.unit,
                                                         scale_factor=source.scale_factor),
                                            dtype=float)
            part["outlier"] = flag
            if include_time:
                part["time"] = ch.time
            n_out += int(flag.sum())
            sink.write(**part)
        path = sink.close()
    return LoopStream(path, source.n, tuple(cols), n_out, skipped, ranges.report(),
                      scan.passes + spikes.passes + 2, None if rms is None else rms.rms(),
                      None if stability is None else stability.report())
