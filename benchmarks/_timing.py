"""Timing helper shared by the benchmark scripts (ratios in one run, never absolute limits)."""

from __future__ import annotations

import time


def best_of(fn, repeat: int) -> float:
    """Shortest wall time of ``repeat`` calls of ``fn()`` (the least disturbed by other load)."""
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)
