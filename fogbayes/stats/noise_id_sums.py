r"""One pass over a series for every lag-1 autocorrelation the noise identification needs.

:func:`fogbayes.stats.noise_id._alpha_of_means` computes, for the finite values
:math:`x_0 \dots x_{N-1}` of the cluster means, the lag-1 autocorrelation of

* :math:`d = 0`: the residual of a straight-line fit, :math:`w_i = x_i - \bar x - b t_i`,
  :math:`t_i = i - (N-1)/2`, :math:`b = \sum t_i x_i / \sum t_i^2`;
* :math:`d \ge 1`: the ``d``-times differenced series, mean removed (the line only adds a
  constant to a difference, which the mean removes).

Each is :math:`r_1 = \sum_{i<N'-1} s_i s_{i+1} / \sum s_i^2` of a mean-zero series ``s``,
so it follows from the sums :math:`\sum s`, :math:`\sum s^2`, :math:`\sum s_i s_{i+1}`,
the end values and, for ``d = 0``, :math:`\sum i\,x_i` (expanded in :func:`lag1_from_sums`).
:func:`lag1_sums` gathers all of them in one compiled pass (NumPy needed about fifteen
passes: the filter copy, the line, the means, the products, each difference). Values are
shifted by the first finite value so that a large offset does not cancel digits.

Cancellation can still remain in ``d = 0`` when the straight line carries almost all of the
variance (a ramp): :func:`lag1_from_sums` returns None then (the residual energy is below
1e-6 of the centred energy) and the caller uses the two-pass NumPy path.
"""

from __future__ import annotations

import numpy as np

from .._numba import numba

#: Cancellation guard: the d = 0 residual energy must keep at least this share of the
#: centred energy for the one-pass sums to keep ~10 significant digits.
MIN_RESIDUAL_SHARE = 1e-6
#: Sums per difference order: sum, sum of squares, lag-1 products, first, last.
_FIELDS = 5
#: Highest difference order formed (Hadamard's dmax).
DMAX = 3


@numba.njit(cache=True, nogil=True)
def _lag1_sums(z):
    """[N, sum i*x, then per d = 0..3: sum, sumsq, lag-1 products, first, last].

    Orders 0-3 are always formed (Hadamard needs 3). The first four finite values start
    the differences; the main loop then has no branch but the finite test, and keeps every
    sum in a register.
    """
    head = np.zeros(4)
    n = 0
    i = 0
    while i < z.shape[0] and n < 4:
        if z[i] - z[i] == 0.0:
            head[n] = z[i]
            n += 1
        i += 1
    out = np.zeros(2 + _FIELDS * (DMAX + 1))
    if n < 4:  # too short for the identification anyway (it needs 30 points)
        out[0] = n
        return out
    c = head[0]
    x0, x1, x2, x3 = 0.0, head[1] - c, head[2] - c, head[3] - c
    u1, u2, u3 = x1 - x0, x2 - x1, x3 - x2
    w2, w3 = u2 - u1, u3 - u2
    e3 = w3 - w2
    s0 = x1 + x2 + x3
    q0 = x1 * x1 + x2 * x2 + x3 * x3
    p0 = x1 * x2 + x2 * x3
    six = x1 + 2.0 * x2 + 3.0 * x3
    s1, q1, p1 = u1 + u2 + u3, u1 * u1 + u2 * u2 + u3 * u3, u1 * u2 + u2 * u3
    s2, q2, p2 = w2 + w3, w2 * w2 + w3 * w3, w2 * w3
    s3, q3, p3 = e3, e3 * e3, 0.0
    lx, lu, lw, le = x3, u3, w3, e3
    k = 4.0
    for j in range(i, z.shape[0]):
        v = z[j]
        if not v - v == 0.0:  # NaN or inf: the cluster is dropped, its neighbours adjoin
            continue
        x = v - c
        u = x - lx
        w = u - lu
        e = w - lw
        six += k * x
        s0 += x
        q0 += x * x
        p0 += lx * x
        s1 += u
        q1 += u * u
        p1 += lu * u
        s2 += w
        q2 += w * w
        p2 += lw * w
        s3 += e
        q3 += e * e
        p3 += le * e
        lx, lu, lw, le = x, u, w, e
        k += 1.0
    out[0] = k
    out[1] = six
    out[2:7] = (s0, q0, p0, x0, lx)
    out[7:12] = (s1, q1, p1, u1, lu)
    out[12:17] = (s2, q2, p2, w2, lw)
    out[17:22] = (s3, q3, p3, e3, le)
    return out


def lag1_sums(z: np.ndarray) -> np.ndarray:
    """The sums of :func:`_lag1_sums` for float64 ``z`` (NaN values skipped)."""
    return _lag1_sums(np.ascontiguousarray(z, dtype=np.float64))


def _mean_removed_lag1(n, s1, s2, p, first, last) -> float:
    """Lag-1 autocorrelation (biased normalisation) of a series from its sums."""
    if n < 2:
        return 0.0
    mu = s1 / n
    den = s2 - n * mu * mu
    num = p - mu * (2.0 * s1 - first - last) + (n - 1) * mu * mu
    return num / den if den > 0 else 0.0


def lag1_from_sums(sums: np.ndarray, d: int) -> float | None:
    """Lag-1 autocorrelation of difference order ``d`` <= :data:`DMAX` (d = 0: line removed),
    or None if
    the one-pass form would lose digits (use the two-pass path then)."""
    n = sums[0]
    k = 2 + _FIELDS * d
    s1, s2, p, first, last = sums[k:k + _FIELDS]
    if d > 0:
        return _mean_removed_lag1(n - d, s1, s2, p, first, last)
    mu = s1 / n
    tc = (n - 1) / 2.0                      # t_i = i - tc
    stt = n * (n * n - 1.0) / 12.0          # sum t^2
    stx = sums[1] - tc * s1                 # sum t x (sum t = 0)
    b = stx / stt if stt > 0 else 0.0
    centred = s2 - n * mu * mu              # sum (x - mu)^2
    den = centred - b * stx                 # minus b^2 sum t^2: the line's share
    if not den > MIN_RESIDUAL_SHARE * centred:
        return None
    a0, al = first - mu, last - mu          # a_i = x_i - mu at the ends
    t0, tl = -tc, tc
    aa = p - mu * (2.0 * s1 - first - last) + (n - 1) * mu * mu   # sum a_i a_{i+1}
    at_next = (stx - al * tl) - al                                  # sum a_i t_{i+1}
    a_next_t = (stx - a0 * t0) + a0                                 # sum a_{i+1} t_i
    tt = stt - tl * tl - tl                                         # sum t_i t_{i+1}
    num = aa - b * (at_next + a_next_t) + b * b * tt
    return num / den
