"""Thermal-model covariates (T, dT/dt, extra channels) of a streamed record, chunk by chunk.

As :func:`fogbayes.thermal.model.thermal_covariates`, on each chunk plus a halo of ``H`` rows,
with record-wide facts from a :class:`~fogbayes.stream.scan.TimeScan`: ``savgol`` H = w
(identical up to 501 samples, FFT beyond: equal to rounding); ``difference`` / ``paper``
H = ceil(3 W / min step) + 2 (bit-identical). Memory: ``rows + 2 H`` rows.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Iterator
from typing import NamedTuple

import numpy as np

from ..errors import FogbayesError, MissingColumnError, TooShortError
from ..thermal.model import ThermalSpec
from ..preprocess.temperature_rate import (
    _whole_run_slope,
    local_poly_slope,
    ls_slope,
    rates_from_means,
    savgol_slope_grid,
)
from .scan import TimeScan
from .sources import Chunk, RecordSource

MAX_HALO = 50_000_000  # rows; beyond this the window would not be "bounded memory" any more


class Plan(NamedTuple):
    """How to compute the covariates of one window (fixed for the whole record)."""

    spec: ThermalSpec
    method: str          # savgol | difference | paper | none
    window_s: float
    w: int               # Savitzky-Golay window in samples
    polyorder: int
    slack: float         # block-grid tolerance (s), as fogbayes.preprocess.blocks.time_slack
    halo: int            # rows added on each side of a chunk
    channels: tuple      # indices into the source's temperature columns, see _channels


def make_plan(source: RecordSource, scan: TimeScan | None, spec: ThermalSpec, *,
              rate_method: str, rate_window_s: float, polyorder: int = 2) -> Plan:
    """Check the request as the in-memory code would and fix the halo."""
    channels = _channels(source, spec)
    if spec.rate_order == 0:
        return Plan(spec, "none", 0.0, 0, polyorder, 0.0, 0, channels)
    if scan is None:
        raise FogbayesError("a temperature-rate covariate needs the time scan",
                            fix="pass scan=scan_time(source)")
    method = {"savgol": "savgol", "difference": "difference", "paper": "paper"}.get(rate_method)
    if method is None:
        raise FogbayesError(f"unknown temperature-rate method '{rate_method}'",
                            column="rate_method", fix="use 'savgol', 'difference' or 'paper'")
    w_s, dt = float(rate_window_s), scan.dt_median
    # the checks of fogbayes.preprocess._checks.check_window, on the scanned facts
    if not np.isfinite(w_s) or w_s <= 0:
        raise FogbayesError(f"window_s must be a positive number of seconds, got {rate_window_s!r}",
                            column="window_s", fix="pass e.g. window_s=1.0")
    if w_s < dt * (1 - 1e-9):
        raise TooShortError(f"window_s={w_s:g} s is shorter than the sample interval {dt:g} s",
                            column="window_s", fix=f"use window_s >= {dt:g} s")
    n_blocks = 1 if method == "savgol" else 2
    span = scan.t_last - scan.t_first + dt
    if n_blocks * w_s > span * (1 + 1e-9):
        raise TooShortError(f"window_s={w_s:g} s is too long for the record ({span:g} s)",
                            column="window_s", fix="use a shorter window or a longer record")
    w = round(w_s / dt)
    w = max(w + 1 - w % 2, polyorder + 1 + (polyorder + 1) % 2, 3)
    slack = max(1e-3 * dt, 16 * float(np.spacing(scan.t_absmax)))
    halo = w if method == "savgol" else math.ceil(3 * w_s / scan.dt_min) + 2
    if halo > MAX_HALO:
        raise FogbayesError(f"the temperature-rate window needs {halo} rows of context "
                            f"(smallest time step {scan.dt_min:g} s)", column="time",
                            fix="remove near-duplicate time stamps or compensate in memory")
    return Plan(spec, method, w_s, w, polyorder, slack, halo, channels)


def _channels(source: RecordSource, spec: ThermalSpec) -> tuple:
    names = list(source.temperature_names)

    def idx(name: str) -> int:
        if not names:
            raise MissingColumnError("the recording has no temperature channel",
                                     file=source.source, column="temperature",
                                     fix="add a 'temperature' column in deg C")
        if name == "":
            return 0
        if name not in names:
            raise MissingColumnError(f"no temperature channel '{name}' (have {names})",
                                     file=source.source, column=name,
                                     fix="name an existing channel or add the column")
        return names.index(name)

    grad = (idx(spec.gradient[0]), idx(spec.gradient[1])) if spec.gradient else ()
    return (idx(spec.temperature), tuple(idx(nm) for nm in spec.extra), grad)


# -- the temperature rate on a window ----------------------------------------------------------
def _runs(scan: TimeScan, row0: int, size: int):
    """(run, local start, local stop, whole run inside) for runs meeting the window."""
    b = scan.bounds
    first = int(np.searchsorted(b, row0, side="right")) - 1
    for r in range(first, b.size - 1):
        ga, gb = int(b[r]), int(b[r + 1])
        if ga >= row0 + size:
            break
        yield r, max(ga, row0) - row0, min(gb, row0 + size) - row0, ga >= row0 and gb <= row0 + size


def _savgol(plan: Plan, scan: TimeScan, t, T, row0):
    out = np.full(t.size, np.nan)  # NaN = not computable here (only ever in the halo)
    w, p = plan.w, plan.polyorder
    for r, a, b, whole in _runs(scan, row0, t.size):
        run_len = int(scan.bounds[r + 1] - scan.bounds[r])
        if run_len < w:
            if whole:
                out[a:b] = _whole_run_slope(t[a:b], T[a:b], p)
            continue
        if b - a < w:
            continue
        if scan.run_dt_max[r] - scan.run_dt_min[r] <= 1e-9 * scan.run_dt_mean[r]:
            out[a:b] = savgol_slope_grid(T[a:b], w, p, float(scan.run_dt_mean[r]))
        else:
            out[a:b] = local_poly_slope(t[a:b], T[a:b], w, p)
    return out


def _difference(plan: Plan, scan: TimeScan, t, T, row0, align):
    """:func:`fogbayes.preprocess.temperature_rate._difference` on the run parts in a window."""
    out = np.full(t.size, np.nan)
    for r, a, b, whole in _runs(scan, row0, t.size):
        ts, Ts = t[a:b], T[a:b]
        k = np.floor((ts - scan.run_t0[r] + plan.slack) / plan.window_s).astype(np.int64)
        new = np.r_[True, k[1:] != k[:-1]]
        gid = np.cumsum(new) - 1
        nb = int(gid[-1]) + 1
        head = np.flatnonzero(new)
        first = ts[head]
        cnt = np.bincount(gid, minlength=nb)
        rel = np.bincount(gid, weights=ts - first[gid], minlength=nb) / cnt
        tm, Tm = first + rel, np.bincount(gid, weights=Ts, minlength=nb) / cnt
        if whole or nb >= 2:
            seg = np.zeros(nb, np.int64)
            out[a:b] = rates_from_means(seg, tm, Tm, np.zeros(ts.size, np.int64), ts, gid,
                                        align, lambda s, ts=ts, Ts=Ts: ls_slope(ts, Ts))
        if not whole and nb < 2:
            out[a:b] = np.nan  # a run shorter than two blocks is only ever seen whole
    return out


def window_covariates(plan: Plan, scan: TimeScan | None, t, temps, row0) -> np.ndarray:
    """Covariates (rows, c) of a window starting at global row ``row0``."""
    i_T, i_extra, grad = plan.channels
    T = temps[:, i_T]
    cols = [T]
    if plan.method == "savgol":
        cols.append(60.0 * _savgol(plan, scan, t, T, row0))
    elif plan.method in ("difference", "paper"):
        align = "interp" if plan.method == "difference" else "hold"
        cols.append(60.0 * _difference(plan, scan, t, T, row0, align))
    cols += [temps[:, i] for i in i_extra]
    if grad:
        cols.append(temps[:, grad[0]] - temps[:, grad[1]])
    return np.column_stack(cols)


def covariate_chunks(source: RecordSource, plan: Plan, scan: TimeScan | None, rows: int,
                     fields=("time", "output", "temperatures")) -> Iterator[tuple[Chunk, np.ndarray]]:
    """(chunk, covariates of its rows) for every chunk of ``source``."""
    if plan.method == "none":
        for ch in source.chunks(rows, fields=fields):
            yield ch, window_covariates(plan, scan, ch.time, ch.temperatures, ch.start)
        return
    need = tuple(dict.fromkeys(("time", "temperatures") + tuple(fields)))
    it = source.chunks(rows, fields=need)
    buf: deque[Chunk] = deque()
    done = False

    def rows_after(i):  # rows held after buffered chunk i
        return sum(c.n for c in list(buf)[i + 1:])

    idx = 0  # index in buf of the chunk to emit
    while True:
        while not done and (len(buf) <= idx or rows_after(idx) < plan.halo):
            nxt = next(it, None)
            if nxt is None:
                done = True
            else:
                buf.append(nxt)
        if len(buf) <= idx:
            return
        cur = buf[idx]
        lo, hi = cur.start - plan.halo, cur.start + cur.n + plan.halo
        parts = [c for c in buf if c.start + c.n > lo and c.start < hi]
        row0 = max(parts[0].start, lo)
        t = np.concatenate([c.time for c in parts])
        temps = np.concatenate([c.temperatures for c in parts])
        a = row0 - parts[0].start
        b = a + min(hi, parts[-1].start + parts[-1].n) - row0
        z = window_covariates(plan, scan, t[a:b], temps[a:b], row0)
        off = cur.start - row0
        yield cur, z[off:off + cur.n]
        idx += 1
        while buf and buf[0].start + buf[0].n <= cur.start + cur.n - plan.halo and idx > 0:
            buf.popleft()
            idx -= 1
