"""Bias and bias stability (paper 004 eqs. 12-13) of many sensors at once.

:func:`segment_reports` returns, for every sensor, exactly the document of
:func:`fogbayes.metrics.segment_report`::

    B0 = mean(F),   Bs(W) = std_{n-1}( means of F over the complete W-second blocks )

on the whole record and on each soak/ramp segment, before and after compensation.

What makes it fast is that a lab samples its gyros with one clock and soaks them in one
chamber: many sensors share a time vector and the same segment bounds. The block layout of
a (time vector, segment, window) is built once (:func:`fogbayes.preprocess.blocks.block_index`,
the same function the single-sensor path uses) and every sensor that shares it gets its
block sums from one reduction over a (sensors, samples) array (:func:`block_sums`: a reshape
on a regular grid, ``numpy.add.reduceat`` otherwise). Sensors with a
clock or segments of their own still work; they share less. Numbers equal the single-sensor
path to rounding (block sums in a different order: ~1e-15 relative).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..errors import TooShortError
from ..metrics import DEFAULT_WINDOWS, improvement_pct
from ..preprocess.blocks import block_index


def block_sums(x: np.ndarray, start: np.ndarray, stop: np.ndarray) -> np.ndarray:
    """Row-wise sums of x (rows, n) over sample ranges [start_j, stop_j) (increasing)."""
    length = stop - start
    if length.size and np.all(length == length[0]) and np.all(start[1:] == stop[:-1]):
        # a regular grid without gaps: equal, adjacent blocks are a reshape (no copy)
        a, b = int(start[0]), int(stop[-1])
        return x[:, a:b].reshape(x.shape[0], length.size, int(length[0])).sum(axis=2)
    edges = np.column_stack([start, stop]).ravel()
    padded = np.concatenate([x, np.zeros((x.shape[0], 1))], axis=1)  # reduceat needs stop < len
    return np.add.reduceat(padded, edges, axis=1)[:, ::2]


def block_means(x: np.ndarray, start: np.ndarray, stop: np.ndarray) -> np.ndarray:
    """Row-wise means of x over sample ranges [start_j, stop_j)."""
    return block_sums(x, start, stop) / (stop - start)


class _Layouts:
    """Block layouts per (time vector, sample range, window), built once each."""

    def __init__(self):
        self._cache: dict = {}

    def get(self, tkey, t: np.ndarray, a: int, b: int, w: float):
        key = (tkey, a, b, w)
        if key not in self._cache:
            try:
                bi = block_index(t[a:b], w, partial="drop")
                self._cache[key] = (bi.start, bi.stop) if bi.start.size >= 2 else None
            except TooShortError:  # as metrics.stability_report: the window is left out
                self._cache[key] = None
        return self._cache[key]


def _report(before: np.ndarray, after: np.ndarray, t: np.ndarray, tkey, a: int, b: int,
            windows: Sequence[float], layouts: _Layouts) -> list[dict]:
    """stability_report of rows ``before``/``after`` (sensors x samples) on samples a:b."""
    x = np.concatenate([before[:, a:b], after[:, a:b]])
    k = before.shape[0]
    b0 = np.mean(x, axis=1)
    rows = [[] for _ in range(k)]
    for w in windows:
        lay = layouts.get(tkey, t, a, b, float(w))
        if lay is None:
            continue
        bs = np.std(block_means(x, *lay), axis=1, ddof=1).tolist()  # Python floats at once
        for s in range(k):
            bs_b, bs_a = bs[s], bs[k + s]
            rows[s].append({"window_s": float(w), "before": bs_b, "after": bs_a,
                            "improvement_pct": improvement_pct(bs_b, bs_a)})
    duration = float(t[b - 1] - t[a])
    b0 = b0.tolist()
    return [{"bias_before": b0[s], "bias_after": b0[k + s],
             "duration_s": duration, "stability": rows[s]} for s in range(k)]


def segment_reports(before: Sequence[np.ndarray], after: Sequence[np.ndarray],
                    times: Sequence[np.ndarray], segments: Sequence[Sequence] = (), *,
                    windows: Sequence[float] = DEFAULT_WINDOWS) -> list[dict]:
    """``segment_report`` of every sensor (same-length records; see the module doc).

    ``before``, ``after``, ``times``: one (n,) array per sensor (or (sensors, n) arrays);
    ``segments``: per sensor, objects with ``kind``, ``start``, ``stop`` (sample rows).
    """
    before = np.asarray(before, dtype=float)
    after = np.asarray(after, dtype=float)
    times = [np.asarray(t, dtype=float) for t in times]
    S, n = before.shape
    segments = list(segments) or [()] * S
    tkeys: dict[bytes, int] = {}
    tid = [tkeys.setdefault(t.tobytes(), len(tkeys)) for t in times]
    # every (time vector, range) with the sensors that need it
    jobs: dict[tuple, list[int]] = {}
    plan = []
    for s in range(S):
        ranges = [(0, n, None)] + [(int(g.start), int(g.stop), g) for g in segments[s]
                                    if g.stop - g.start >= 2]
        plan.append(ranges)
        for a, b, _ in ranges:
            jobs.setdefault((tid[s], a, b), []).append(s)
    layouts = _Layouts()
    done: dict[tuple[int, int, int], dict] = {}
    for (tk, a, b), who in jobs.items():
        idx = np.asarray(who)
        reps = _report(before[idx], after[idx], times[who[0]], tk, a, b, windows, layouts)
        for s, rep in zip(who, reps):
            done[(s, a, b)] = rep
    out = []
    for s in range(S):
        t = times[s]
        full, *segs = plan[s]
        out.append({"full": done[(s, 0, n)], "segments": [
            {"kind": g.kind, "start_s": float(t[a]), "stop_s": float(t[b - 1]), **done[(s, a, b)]}
            for a, b, g in segs]})
    return out
