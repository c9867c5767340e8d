"""Covariates of a recording and the uniform block grid the evidence works on.

Blocks of ``dt`` s from the first sample; empty blocks are missing, never filled.
ybar_b = mean of the unflagged samples, Var_white(ybar_b) = s2 m_ref / m_b. dT/dt (deg C/min,
first channel): centred Savitzky-Golay slope (order 2) over ``rate_window_s``
(:func:`fogbayes.preprocess.temperature_rate.savgol_slope_grid`), spline-interpolated to the
samples, with kinks at programme corners kept (:mod:`fogbayes.preprocess.corners`).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from scipy.interpolate import CubicSpline

from ..errors import TooShortError
from .operating_time import operating_time
from .temperature_rate import savgol_slope_grid
from .corners import corner_reach, find_corners, replace_near_corners


class Covariates(NamedTuple):
    """Drivers of the candidate effects, one row per sample (or per block).

    t: s from the first sample; T: (n, k) deg C; names: channel names; Tdot: (n,) deg C/min
    of the first channel (None without temperature); omega: (n,) deg/s or None;
    duration: record span (s); op_time: operating time of a rate-table run (s since the
    last input-rate step, :func:`fogbayes.preprocess.operating_time.operating_time`) or None.
    """

    t: np.ndarray
    T: np.ndarray
    names: tuple[str, ...]
    Tdot: np.ndarray | None
    omega: np.ndarray | None
    duration: float
    op_time: np.ndarray | None = None  # s since the last input-rate step (paper 000's t)

    @property
    def n_temps(self) -> int:
        return int(self.T.shape[1])


class BlockGrid(NamedTuple):
    """Uniform block grid: ``index`` (n,) block of each sample, ``use`` (n,) sample used.

    count (nb,) used samples per block; mask (nb,) 1.0 observed / 0.0 missing;
    w (nb,) white-variance weight m_ref / count (1 where missing); t (nb,) block centre (s).
    """

    dt: float
    index: np.ndarray
    use: np.ndarray
    count: np.ndarray
    mask: np.ndarray
    w: np.ndarray
    t: np.ndarray

    @property
    def n(self) -> int:
        return int(self.count.size)

    def mean(self, x: np.ndarray) -> np.ndarray:
        """Block means of (n,) or (n, k) values over used samples; 0 in missing blocks."""
        x = np.asarray(x, dtype=float)
        flat = x.ndim == 1
        x2 = x[:, None] if flat else x
        idx, use = self.index[self.use], self.use
        out = np.zeros((self.n, x2.shape[1]))
        cnt = np.maximum(self.count, 1)
        for j in range(x2.shape[1]):
            out[:, j] = np.bincount(idx, weights=x2[use, j], minlength=self.n) / cnt
        return out[:, 0] if flat else out


def block_step(span: float, fs: float, *, target_blocks: int = 2500, max_dt: float = 10.0,
               min_dt: float | None = None) -> float:
    """``dt = m / fs`` with m the smallest integer giving at most ``target_blocks`` blocks
    over ``span`` s, but never more than ``max_dt`` unless the record would then exceed
    3 x target blocks (and at least ``min_dt`` when given)."""
    step = 1.0 / float(fs)
    m = max(1, int(math.ceil(span / step / target_blocks)))
    if min_dt is not None:
        m = max(m, int(math.ceil(min_dt / step - 1e-9)))
    if m * step > max_dt and span / max_dt <= 3 * target_blocks:
        m = max(1, int(math.floor(max_dt / step + 1e-9)))
    return m * step


def block_index(rel: np.ndarray, dt: float, fs: float) -> np.ndarray:
    """Block of each sample at ``rel`` s from the first (a stamp a hair early stays in)."""
    step = 1.0 / float(fs)
    return np.floor(rel / dt + 1e-6 * step / dt).astype(np.int64)


def grid_of_counts(dt: float, count: np.ndarray) -> BlockGrid:
    """The grid's per-block parts (counts, mask, weights, centres) from the used-sample
    counts; ``index``/``use`` are left empty (a stream keeps no per-sample arrays)."""
    nb = count.size
    mask = (count > 0).astype(float)
    m_ref = float(np.median(count[count > 0])) if np.any(count > 0) else 1.0
    w = np.where(count > 0, m_ref / np.maximum(count, 1), 1.0)
    centre = (np.arange(nb) + 0.5) * dt
    if int(mask.sum()) < 20:
        raise TooShortError(f"only {int(mask.sum())} blocks of {dt:g} s hold data",
                            column="time", fix="give a longer record (the loop needs >= 20 blocks)")
    empty = np.zeros(0, np.int64)
    return BlockGrid(dt, empty, empty.astype(bool), count, mask, w, centre)


def block_grid(t: np.ndarray, fs: float, *, use: np.ndarray | None = None,
               target_blocks: int = 2500, max_dt: float = 10.0,
               min_dt: float | None = None) -> BlockGrid:
    """Choose ``dt`` (:func:`block_step`) and bin the samples."""
    t = np.asarray(t, dtype=float)
    dt = block_step(float(t[-1] - t[0]), fs, target_blocks=target_blocks, max_dt=max_dt,
                    min_dt=min_dt)
    index = block_index(t - t[0], dt, fs)
    nb = int(index[-1]) + 1
    use = np.ones(t.size, bool) if use is None else np.asarray(use, bool)
    count = np.bincount(index[use], minlength=nb).astype(float)
    return grid_of_counts(dt, count)._replace(index=index, use=use)


def _fill(x: np.ndarray, mask: np.ndarray, tb: np.ndarray) -> np.ndarray:
    ok = mask > 0
    return np.interp(tb, tb[ok], x[ok])


def rate_window(grid: BlockGrid, window_s: float = 60.0) -> int:
    """Savitzky-Golay window in blocks (odd, >= 5; 0 when the record is shorter than 5)."""
    nb = grid.n
    wl = round(window_s / grid.dt)
    wl = max(5, wl + 1 - wl % 2)
    if wl > nb:
        wl = nb - 1 + nb % 2 if nb >= 5 else 0
    return wl


def centred_block_temperature(T_mean: np.ndarray, t_mean: np.ndarray, mask: np.ndarray,
                              tb: np.ndarray, dt: float,
                              wl: int) -> tuple[np.ndarray, np.ndarray]:
    """Block-mean temperature at the block centres and its slope (deg C/s) per block.

    A block's mean ``T_mean`` is the temperature at its samples' mean time ``t_mean``, which
    is off the centre in a partial block or where a time stamp falls across a boundary; it
    is moved to the centre to first order, Tb - slope (t_mean - t_centre), so that a steep
    ramp does not look rough (on a 1 deg C/min ramp sampled at 10 Hz the offsets of 0.05 s
    made false corners).
    """
    Tb = _fill(T_mean, mask, tb)
    if wl < 5:
        return Tb, np.gradient(Tb, dt)
    slope = savgol_slope_grid(Tb, wl, 2, dt)
    shift = _fill(t_mean, mask, tb) - tb
    if np.any(np.abs(shift) > 1e-9 * dt):
        Tb = Tb - slope * shift
        slope = savgol_slope_grid(Tb, wl, 2, dt)
    return Tb, slope


def block_temperature(grid: BlockGrid, T0: np.ndarray, t_rel: np.ndarray,
                      wl: int) -> tuple[np.ndarray, np.ndarray]:
    """:func:`centred_block_temperature` of samples binned on ``grid``."""
    return centred_block_temperature(grid.mean(T0), grid.mean(t_rel), grid.mask, grid.t,
                                     grid.dt, wl)


class RateCurve(NamedTuple):
    """dT/dt of a record as a function of time: a cubic spline through the block slopes,
    with the kinked fit near each chamber corner. Built once from the block means; called
    on any samples (all of them, or a stream's chunk)."""

    spline: CubicSpline
    tb: np.ndarray                    # block centres (s from the first sample)
    corners: list                     # (time, beta) of corners.find_corners
    half: float                       # the corner fit's reach, s

    def __call__(self, t_rel: np.ndarray) -> np.ndarray:
        """deg C/min at ``t_rel`` (s from the record's first sample)."""
        # A cubic spline, not linear interpolation: kinks every block would put a comb of
        # lines at k / dt into every model that uses dT/dt.
        rate = self.spline(np.clip(t_rel, self.tb[0], self.tb[-1]))
        if self.corners:  # the chamber's corners are real kinks: keep them (corners.py)
            rate = replace_near_corners(self.corners, self.half, t_rel, rate)
        return 60.0 * rate


def rate_curve(T_mean: np.ndarray, t_mean: np.ndarray, mask: np.ndarray, tb: np.ndarray,
               dt: float, wl: int) -> RateCurve:
    """The :class:`RateCurve` of block means (``wl`` from :func:`rate_window`)."""
    Tb, slope = centred_block_temperature(T_mean, t_mean, mask, tb, dt, wl)
    corners = find_corners(tb, Tb, wl) if wl >= 5 and Tb.size >= 2 else []
    return RateCurve(CubicSpline(tb, slope), tb, corners, corner_reach(tb, wl))


def temperature_rate(grid: BlockGrid, T0: np.ndarray, t_rel: np.ndarray,
                     window_s: float = 60.0) -> np.ndarray:
    """dT/dt (deg C/min) per sample: Savitzky-Golay slope of block means, interpolated,
    with the chamber's corners kept (module docstring)."""
    return rate_curve(grid.mean(T0), grid.mean(t_rel), grid.mask, grid.t, grid.dt,
                      rate_window(grid, window_s))(t_rel)


def covariates_of(rec, grid: BlockGrid, *, rate_window_s: float = 60.0) -> Covariates:
    """Per-sample covariates of a :class:`~fogbayes.data.Recording`."""
    t = np.asarray(rec.time, float) - float(rec.time[0])
    T = np.asarray(rec.temperatures, float)
    Tdot = temperature_rate(grid, T[:, 0], t, rate_window_s) if T.shape[1] else None
    omega = None if rec.input_rate is None else np.asarray(rec.input_rate, float)
    op = None
    if omega is not None:
        op = operating_time(t, omega, convention="cell")
    return Covariates(t, T, tuple(rec.temperature_names), Tdot, omega, float(t[-1]), op)


def block_covariates(cov: Covariates, grid: BlockGrid) -> Covariates:
    """Block means of every covariate (missing blocks interpolated, so filters can run)."""
    def m(x):
        if x is None:
            return None
        b = grid.mean(x)
        if b.ndim == 1:
            return _fill(b, grid.mask, grid.t)
        return np.column_stack([_fill(b[:, j], grid.mask, grid.t) for j in range(b.shape[1])]) \
            if b.shape[1] else b
    return Covariates(grid.t.copy(), m(cov.T), cov.names, m(cov.Tdot), m(cov.omega),
                      cov.duration, m(cov.op_time))
