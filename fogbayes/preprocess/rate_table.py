"""Plateaus (T_i, Omega_j) of a rate-table run, for paper 000's temperature x rate grid.

On a plateau: input-rate range over ``stable_s`` <= ``rate_tolerance`` and |Savitzky-Golay dT/dt|
<= ``rate_threshold``. Runs are cut at gaps and steps, trimmed by ``trim_s``, dropped if shorter
than ``min_duration`` or spanning > 2 ``rate_tolerance``; cells are grouped into levels by
``temperature_tolerance`` and ``rate_tolerance``. ``schedule=[(t_start, t_stop, T, Omega), ...]``
gives the cells directly.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..errors import ArgumentError, ShapeError, TooShortError
from ._checks import (GAP_FACTOR, as_1d, check_time, check_window, median_step, same_length,
                      segment_bounds)
from .temperature_rate import temperature_rate


class RateCell(NamedTuple):
    """One plateau: samples ``start:stop`` (stop exclusive), first/last sample times,
    mean (or nominal) temperature (deg C) and input rate (deg/s), level indices (i, j)."""

    start: int
    stop: int
    t_start: float
    t_stop: float
    temperature: float
    rate: float
    i: int
    j: int


class RateTable(NamedTuple):
    """Cells in time order and the temperature and rate levels they index."""

    cells: tuple[RateCell, ...]
    temperature_levels: np.ndarray
    rate_levels: np.ndarray

    def grid(self) -> np.ndarray:
        """(n_T, n_Omega) int array: the index in ``cells`` of each (T_i, Omega_j), -1 if none
        (the last cell wins when a pair was visited twice)."""
        g = -np.ones((self.temperature_levels.size, self.rate_levels.size), int)
        for c, cell in enumerate(self.cells):
            g[cell.i, cell.j] = c
        return g


def levels(values: np.ndarray, tolerance: float) -> tuple[np.ndarray, np.ndarray]:
    """Group sorted ``values`` where consecutive ones differ by more than ``tolerance``.

    Returns the level means and each value's level index.
    """
    order = np.argsort(values, kind="stable")
    v = values[order]
    lev_sorted = np.r_[0, np.cumsum(np.diff(v) > tolerance)]
    idx = np.empty(values.size, int)
    idx[order] = lev_sorted
    means = np.array([v[lev_sorted == k].mean() for k in range(int(lev_sorted[-1]) + 1)]) \
        if values.size else np.zeros(0)
    return means, idx


def segment_rate_table(time, input_rate=None, temperature=None, *, schedule=None,
                       rate_tolerance: float = 0.01, temperature_tolerance: float = 2.0,
                       rate_threshold: float = 0.1 / 60.0, min_duration: float = 10.0,
                       trim_s: float = 0.0, stable_s: float | None = None,
                       smooth_s: float = 60.0, gap_factor: float = GAP_FACTOR) -> RateTable:
    """Find the (T_i, Omega_j) plateaus of a rate-table run (see the module doc).

    Args:
        time: (n,) s.
        input_rate: (n,) reference rate (deg/s); needed unless ``schedule`` is given.
        temperature: (n,) deg C, or None (one temperature level).
        schedule: optional list of (t_start, t_stop, T, Omega) replacing detection.
        rate_tolerance: deg/s; steadiness of the rate and spacing of rate levels.
        temperature_tolerance: deg C; spacing of temperature levels.
        rate_threshold: deg C/s; steadiness of the temperature.
        min_duration: shortest plateau kept (s).
        trim_s: seconds dropped at the start of each plateau (settling).
        stable_s: window of the rate-steadiness test (s); default 5 samples.
        smooth_s: window of the temperature-rate smoother (s).
    """
    t = check_time(time)
    T = None if temperature is None else as_1d(temperature, "temperature")
    W = None if input_rate is None else as_1d(input_rate, "input_rate")
    same_length(time=t, input_rate=W, temperature=T)
    if schedule is not None:
        return _from_schedule(t, schedule, float(trim_s), rate_tolerance, temperature_tolerance)
    if W is None:
        raise ArgumentError("plateau detection needs the reference input rate",
                            column="input_rate", fix="pass input_rate=... or a schedule")
    dt = median_step(t)
    w = 5 if stable_s is None else max(3, int(round(float(stable_s) / dt)) | 1)
    steady = _moving_range(W, w) <= rate_tolerance
    if T is not None:
        check_window(smooth_s, t, name="smooth_s")
        rT = temperature_rate(t, T, method="savgol", window_s=smooth_s, polyorder=1,
                              gap_factor=gap_factor)
        steady &= np.abs(rT) <= rate_threshold
    bounds = segment_bounds(t, gap_factor)
    seg = np.repeat(np.arange(bounds.size - 1), np.diff(bounds))
    change = np.r_[True, (steady[1:] != steady[:-1]) | (seg[1:] != seg[:-1])]
    starts = np.flatnonzero(change)
    stops = np.r_[starts[1:], t.size]
    raw = []
    for a, b in zip(starts, stops):
        if not steady[a]:
            continue
        a = int(np.searchsorted(t, t[a] + trim_s, side="left")) if trim_s > 0 else int(a)
        if a >= b or t[b - 1] - t[a] + dt < min_duration or np.ptp(W[a:b]) > 2 * rate_tolerance:
            continue
        raw.append((a, int(b), np.nan if T is None else float(T[a:b].mean()), float(W[a:b].mean())))
    if not raw:
        raise TooShortError("no plateau found: the input rate or the temperature is never "
                            f"steady for {min_duration:g} s", column="input_rate",
                            fix="lower min_duration, raise rate_tolerance, or pass a schedule")
    return _build(t, raw, rate_tolerance, temperature_tolerance)


def _moving_range(x: np.ndarray, w: int) -> np.ndarray:
    """max - min of x over the centred window of odd width w, the ends extended by their
    edge values (``scipy.ndimage``'s ``mode="nearest"``). Short windows (the default 5
    samples) by a strided view: importing ``scipy.ndimage`` costs ~0.12 s, a twentieth of
    ``fogbayes fit -m composite``; long ones by its O(n) filters."""
    if w > 31:
        from scipy.ndimage import maximum_filter1d, minimum_filter1d

        return maximum_filter1d(x, w, mode="nearest") - minimum_filter1d(x, w, mode="nearest")
    win = np.lib.stride_tricks.sliding_window_view(np.pad(x, w // 2, mode="edge"), w)
    return win.max(axis=1) - win.min(axis=1)


def _build(t, raw, rate_tolerance, temperature_tolerance) -> RateTable:
    temps = np.array([r[2] for r in raw])
    rates = np.array([r[3] for r in raw])
    if np.all(np.isnan(temps)):
        t_lev, ti = np.array([np.nan]), np.zeros(len(raw), int)
    else:
        t_lev, ti = levels(temps, temperature_tolerance)
    r_lev, rj = levels(rates, rate_tolerance)
    cells = tuple(RateCell(a, b, float(t[a]), float(t[b - 1]), Tm, Wm, int(i), int(j))
                  for (a, b, Tm, Wm), i, j in zip(raw, ti, rj))
    return RateTable(cells, t_lev, r_lev)


def _from_schedule(t, schedule, trim_s, rate_tolerance, temperature_tolerance) -> RateTable:
    rows = [tuple(r) for r in schedule]
    raw = []
    for k, row in enumerate(rows):
        if len(row) != 4:
            raise ShapeError(f"schedule entry {k} has {len(row)} values", column="schedule", row=k,
                             fix="give each entry as (t_start, t_stop, T, Omega)")
        t0, t1, Tn, Wn = map(float, row)
        if not t1 > t0:
            raise ArgumentError(f"schedule entry {k} ends before it starts ({t0:g} -> {t1:g} s)",
                                column="schedule", row=k, fix="give t_stop > t_start")
        a = int(np.searchsorted(t, t0 + trim_s, side="left"))
        b = int(np.searchsorted(t, t1, side="left"))
        if b <= a:
            raise TooShortError(f"schedule entry {k} ({t0:g} .. {t1:g} s) holds no sample"
                                + (f" after trim_s={trim_s:g} s" if trim_s else ""),
                                column="schedule", row=k,
                                fix="check the schedule times against the record's time column")
        raw.append((a, b, Tn, Wn))
    return _build(t, raw, rate_tolerance, temperature_tolerance)
