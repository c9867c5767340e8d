"""The first-order recursive filter, y_t = b0 u_t + z_t, z_{t+1} = b1 u_t + a y_t, down the
columns of U (``z_0`` given, 0 by default).

``scipy.signal.lfilter([b0, b1], [1, -a], U, axis=0, zi=z_0)`` in its own order of operations
(transposed direct form II), so the same numbers to the last bit; a compiled loop because
importing ``scipy.signal`` costs half a second of a ``fogbayes loop`` call. With b = (1, 0) it
is the AR(1) recursion x_t = u_t + a x_{t-1}, x_0 = u_0 (:func:`ar1_filter`): the loop's null
series and the backward sums of its noise covariance; with the lag's b, the first-order lag of
:mod:`fogbayes.effects.lag`. :func:`varying_ar1` is the recursion with a coefficient per step
(the lag on irregular sample times).
"""

from __future__ import annotations

import numpy as np

from .numba_cache import numba


def first_order_filter(b0: float, b1: float, a: float, U, z0=0.0) -> np.ndarray:
    """y (n, k) of U (n, k), or (n,) for one column (module doc); ``z0`` scalar or (k,)."""
    U = np.asarray(U, dtype=float)
    if U.size == 0:
        return U.copy()
    U2 = np.ascontiguousarray(U.reshape(U.shape[0], -1))
    z = np.ascontiguousarray(np.broadcast_to(np.asarray(z0, float), (U2.shape[1],)))
    return _filter(float(b0), float(b1), float(a), U2, z).reshape(U.shape)


def ar1_filter(phi: float, U) -> np.ndarray:
    """x_t = U_t + phi x_{t-1}, x_0 = U_0, down the columns of U."""
    return first_order_filter(1.0, 0.0, phi, U)


def varying_ar1(a, b) -> np.ndarray:
    """y_k = a_k y_{k-1} + b_k (y_{-1} = 0), in order; one compiled loop for every length."""
    return _varying(np.ascontiguousarray(a, dtype=float), np.ascontiguousarray(b, dtype=float))


@numba.njit(cache=True, nogil=True)
def _varying(a, b):  # pragma: no cover (Numba)
    y = np.empty(b.size)
    acc = 0.0
    for k in range(b.size):
        acc = a[k] * acc + b[k]
        y[k] = acc
    return y


@numba.njit(cache=True, nogil=True)
def _filter(b0, b1, a, U, z0):  # pragma: no cover (Numba)
    n, k = U.shape
    y = np.empty((n, k))
    for j in range(k):
        z = z0[j]
        for t in range(n):
            yt = z + b0 * U[t, j]
            z = b1 * U[t, j] + a * yt
            y[t, j] = yt
    return y
