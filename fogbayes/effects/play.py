"""The play (backlash) operator: a rate-independent hysteresis with memory.

P_k = min(max(P_{k-1}, u_k - h), u_k + h), P_0 = u_0, h = width / 2. The loop's column is
(u - P) / h: +1 after heating, -1 after cooling, held through a soak.
"""

from __future__ import annotations

import numpy as np

from ..support.numba_cache import numba


@numba.njit(cache=True)
def _play(u: np.ndarray, h: float, y: float) -> np.ndarray:  # pragma: no cover - compiled
    out = np.empty_like(u)
    for i in range(u.size):
        x = u[i]
        if y < x - h:
            y = x - h
        elif y > x + h:
            y = x + h
        out[i] = y
    return out


def play(u: np.ndarray, width: float, *, initial: float | None = None) -> np.ndarray:
    """P of ``u`` for a play of total ``width`` (module doc); width <= 0 returns ``u``.

    ``initial``: the state before ``u[0]`` (a record read in chunks carries the last P);
    by default P starts at ``u[0]``.
    """
    u = np.ascontiguousarray(u, dtype=float)
    if width <= 0 or u.size == 0:
        return u.copy()
    return _play(u, 0.5 * float(width), float(u[0]) if initial is None else float(initial))
