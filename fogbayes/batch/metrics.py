"""Bias and bias stability (paper 004 eqs. 12-13) of many sensors at once.

:func:`segment_reports` returns per sensor the document of
:func:`fogbayes.stats.stability.segment_report` (B0 = mean(F), Bs(W) = std_{n-1} of W-second
block means; whole record and each segment, before/after), one block layout
(:func:`fogbayes.preprocess.blocks.block_index`) and one :func:`.block_kernels.stability`
call per shared clock.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..errors import TooShortError
from ..stats.stability import DEFAULT_WINDOWS, improvement_pct
from ..preprocess.blocks import block_index
from . import block_kernels


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
    k = before.shape[0]
    lays = [(float(w), layouts.get(tkey, t, a, b, float(w))) for w in windows]
    lays = [(w, lay) for w, lay in lays if lay is not None]
    start = np.concatenate([lay[0] for _, lay in lays] or [np.zeros(0, np.int64)])
    stop = np.concatenate([lay[1] for _, lay in lays] or [np.zeros(0, np.int64)])
    offsets = np.cumsum([0] + [lay[0].size for _, lay in lays])
    b0, bs = block_kernels.stability(before, after, a, b, start, stop, offsets)
    (b0_b, b0_a), (bs_b, bs_a) = b0.tolist(), bs.tolist()
    duration = float(t[b - 1] - t[a])
    return [{"bias_before": b0_b[s], "bias_after": b0_a[s], "duration_s": duration,
             "stability": [{"window_s": w, "before": bs_b[s][j], "after": bs_a[s][j],
                            "improvement_pct": improvement_pct(bs_b[s][j], bs_a[s][j])}
                           for j, (w, _) in enumerate(lays)]}
            for s in range(k)]


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
        rows = slice(None) if len(who) == S else np.asarray(who)  # all sensors: no copy
        reps = _report(before[rows], after[rows], times[who[0]], tk, a, b, windows, layouts)
        for s, rep in zip(who, reps):
            done[(s, a, b)] = rep
    out = []
    for s in range(S):
        t = times[s]
        _, *segs = plan[s]  # the full record's range is first
        out.append({"full": done[(s, 0, n)], "segments": [
            {"kind": g.kind, "start_s": float(t[a]), "stop_s": float(t[b - 1]), **done[(s, a, b)]}
            for a, b, g in segs]})
    return out
