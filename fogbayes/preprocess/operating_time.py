"""Operating time t (s) of every sample of a rate-table run (paper 000's t of U1(T) t):
``"cell"`` (since the last input-rate step, default), ``"temperature"`` (since the
temperature plateau's first cell) or ``"run"`` (since the first sample).
"""

from __future__ import annotations

import numpy as np

from ..errors import FogbayesError

CONVENTIONS = ("cell", "temperature", "run")


class ConventionError(FogbayesError):
    """An unknown operating-time convention."""


def check_convention(convention: str) -> str:
    if convention not in CONVENTIONS:
        raise ConventionError(f"unknown operating-time convention {convention!r}",
                              column="operating_time", fix=f"use one of {', '.join(CONVENTIONS)}")
    return convention


def operating_time(time, input_rate=None, cells=None, *, convention: str = "cell",
                   rate_tolerance: float = 0.01) -> np.ndarray:
    """Operating time t (s) of every sample under ``convention`` (see the module doc).

    ``"cell"`` restarts at every input-rate step (|dW| > ``rate_tolerance`` between
    samples); ``"temperature"`` at the first cell of each run of cells at one temperature
    level (``cells`` from :func:`fogbayes.preprocess.segment_rate_table`); both fall back to ``"run"`` when
    their information is missing.
    """
    time = np.asarray(time, dtype=float)
    check_convention(convention)
    origin_idx = np.zeros(time.size, int)
    if convention == "cell" and input_rate is not None:
        step = np.flatnonzero(np.abs(np.diff(np.asarray(input_rate, float))) > rate_tolerance) + 1
        marks = np.zeros(time.size, int)
        marks[step] = step
        origin_idx = np.maximum.accumulate(marks)
    elif convention == "temperature" and cells:
        marks = np.zeros(time.size, int)
        prev = None
        for c in cells:
            if c.i != prev:
                marks[c.start] = c.start
            prev = c.i
        origin_idx = np.maximum.accumulate(marks)
    return time - time[origin_idx]


def operating_time_chunk(time, input_rate, carry, *, rate_tolerance: float = 0.01):
    """:func:`operating_time` (convention ``"cell"``) of one chunk of a record read in
    order, and the carry for the next chunk: ``carry`` is (time of the current origin, last
    input rate) of the chunks before, None on the first chunk (whose first row is an
    origin). Equal, chunk by chunk, to the whole record's values."""
    t, w = np.asarray(time, dtype=float), np.asarray(input_rate, dtype=float)
    origin_t, prev_w = (None, None) if carry is None else carry
    step = np.abs(np.diff(w, prepend=w[0] if prev_w is None else prev_w)) > rate_tolerance
    if prev_w is None:
        step[0] = True
    idx = np.maximum.accumulate(np.where(step, np.arange(t.size), -1))
    origin = np.where(idx >= 0, t[np.maximum(idx, 0)], origin_t if origin_t is not None else t[0])
    return t - origin, (float(origin[-1]), float(w[-1]))
