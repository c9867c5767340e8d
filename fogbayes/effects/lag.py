"""First-order lag of a sampled signal, tau dL/dt = u - L (the one implementation).

Exact for u linear between samples: L_k = a_k L_{k-1} + (1 - c_k) u_k + (c_k - a_k) u_{k-1},
a_k = exp(-h_k / tau), c_k = tau (1 - a_k) / h_k. Uniform steps by
:func:`~fogbayes.support.first_order_filter.first_order_filter` (``scipy.signal.lfilter``'s
numbers), otherwise the same recursion with each step's own coefficients.
"""

from __future__ import annotations

import numpy as np

from ..support.first_order_filter import first_order_filter, varying_ar1


def first_order_lag(t: np.ndarray, u: np.ndarray, tau: float, *,
                    initial: float | None = None) -> np.ndarray:
    """L(t) of ``tau dL/dt = u - L`` (module doc); tau <= 0 returns ``u`` itself."""
    t, u = np.asarray(t, float), np.asarray(u, float)
    if tau <= 0 or u.size < 2:
        return u.copy()
    y0 = float(u[0]) if initial is None else float(initial)
    h = np.maximum(np.diff(t), 1e-12)
    if np.ptp(h) <= 1e-9 * max(h[0], 1.0):
        a = float(np.exp(-h[0] / tau))
        c = float(-tau * np.expm1(-h[0] / tau) / h[0])  # tau (1 - a) / h without cancellation
        b = [1.0 - c, c - a]
        return first_order_filter(b[0], b[1], a, u, y0 - b[0] * u[0])  # y0 = b0 u0 + z
    a = np.exp(-h / tau)
    c = -tau * np.expm1(-h / tau) / h
    b = (1.0 - c) * u[1:] + (c - a) * u[:-1]
    return varying_ar1(np.concatenate([[0.0], a]), np.concatenate([[y0], b]))
