"""Input checks and the gap rule shared by the preprocessing functions.

Every check raises a specific :class:`fogbayes.errors.FogbayesError` subclass that names
the argument (as ``column``), the first offending row and the fix, so that arrays handed
to preprocessing fail the same way a bad file does.
"""

from __future__ import annotations

import numpy as np

from ..errors import ArgumentError, NonFiniteError, ShapeError, TimeOrderError, TooShortError

#: Two consecutive samples further apart than this many median steps are a gap
#: (the same rule as :meth:`fogbayes.data.Recording.sampling`).
GAP_FACTOR = 1.5


def as_1d(x, name: str) -> np.ndarray:
    """``x`` as a finite float64 vector, or a ShapeError / NonFiniteError naming ``name``."""
    a = np.asarray(x, dtype=float)
    if a.ndim != 1:
        raise ShapeError(f"{name} must be one-dimensional, got shape {a.shape}", column=name,
                         fix=f"pass a single column (e.g. {name}[:, 0] or np.ravel({name}))")
    bad = np.flatnonzero(~np.isfinite(a))
    if bad.size:
        raise NonFiniteError(f"{bad.size} value(s) are NaN or infinite", column=name,
                             row=int(bad[0]), fix="remove or repair those samples first")
    return a


def same_length(**arrays: np.ndarray) -> int:
    """The common length of ``arrays`` (skipping None), or a ShapeError naming the odd one."""
    named = [(k, v) for k, v in arrays.items() if v is not None]
    n = len(named[0][1])
    for k, v in named[1:]:
        if len(v) != n:
            raise ShapeError(f"{k} has {len(v)} samples but {named[0][0]} has {n}", column=k,
                             fix=f"give one {k} value per {named[0][0]} sample")
    return n


def check_time(time, name: str = "time", n_min: int = 2) -> np.ndarray:
    """A strictly increasing, finite time vector with at least ``n_min`` samples."""
    t = as_1d(time, name)
    if t.size < n_min:
        raise TooShortError(f"needs at least {n_min} samples, got {t.size}", column=name,
                            fix="pass a longer record")
    bad = np.flatnonzero(np.diff(t) <= 0)
    if bad.size:
        raise TimeOrderError(f"time is not strictly increasing at row {bad[0] + 1}",
                             column=name, row=int(bad[0]) + 1,
                             fix="sort by time and remove duplicate time stamps")
    return t


def median_step(t: np.ndarray) -> float:
    """Median sample interval (s)."""
    return float(np.median(np.diff(t)))


def segment_bounds(t: np.ndarray, gap_factor: float = GAP_FACTOR) -> np.ndarray:
    """Start indices of the runs between gaps, plus ``len(t)`` at the end.

    A gap is a step longer than ``gap_factor`` times the median step. Runs are
    ``t[b[i]:b[i+1]]``; gaps are never filled.
    """
    dt = np.diff(t)
    cut = np.flatnonzero(dt > gap_factor * np.median(dt)) + 1
    return np.concatenate([[0], cut, [t.size]]).astype(int)


def check_window(window_s: float, t: np.ndarray, *, name: str = "window_s",
                 n_blocks: int = 1) -> float:
    """A window no shorter than one sample interval and fitting ``n_blocks`` times in the record."""
    w = float(window_s)
    if not np.isfinite(w) or w <= 0:
        raise ArgumentError(f"{name} must be a positive number of seconds, got {window_s!r}",
                            column=name, fix=f"pass e.g. {name}=1.0")
    dt = median_step(t)
    # 1e-9 relative slack: a window equal to the step written as 1/fs must pass.
    if w < dt * (1 - 1e-9):
        raise TooShortError(f"{name}={w:g} s is shorter than the sample interval {dt:g} s",
                            column=name, fix=f"use {name} >= {dt:g} s (one sample per block), "
                                             "or read the times in seconds (--time-unit ms, "
                                             "us or ns; time_unit= in fogbayes.load)")
    span = float(t[-1] - t[0] + dt)
    if n_blocks * w > span * (1 + 1e-9):
        need = ("longer than the record" if n_blocks == 1
                else f"too long for {n_blocks} blocks in the record")
        raise TooShortError(f"{name}={w:g} s is {need} ({span:g} s)", column=name,
                            fix=f"use {name} <= {span / n_blocks:g} s or a longer record")
    return w


def check_positive_int(value, name: str, minimum: int = 1) -> int:
    """An integer argument >= ``minimum``."""
    if isinstance(value, bool) or int(value) != value or value < minimum:
        raise ArgumentError(f"{name} must be an integer >= {minimum}, got {value!r}",
                            column=name, fix=f"pass {name}={minimum} or more")
    return int(value)
