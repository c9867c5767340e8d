"""Polynomial detrending on a centred and scaled time basis.

u = (t - t_ref) / t_scale in [-1, 1] (t_ref, t_scale the mid-point and half-span); least
squares on a Legendre basis, reported as monomials: trend(t) = sum_k coef[k] u^k, residual = x - trend.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.polynomial import legendre

from ..errors import TooShortError
from ._checks import as_1d, check_positive_int, same_length


class Detrended(NamedTuple):
    """Result of :func:`detrend`.

    residual: x - trend, shape (n,).
    trend: the fitted polynomial at every sample, shape (n,).
    coef: monomial coefficients in the scaled time u, lowest order first, shape (p+1,).
    t_ref, t_scale: u = (t - t_ref) / t_scale.
    """

    residual: np.ndarray
    trend: np.ndarray
    coef: np.ndarray
    t_ref: float
    t_scale: float

    def evaluate(self, t) -> np.ndarray:
        """The trend polynomial at times ``t`` (e.g. on another grid)."""
        u = (np.asarray(t, dtype=float) - self.t_ref) / self.t_scale
        return np.polynomial.polynomial.polyval(u, self.coef)


def detrend(x, t=None, order: int = 1, *, mask=None) -> Detrended:
    """Remove a least-squares polynomial trend of ``order`` in time from ``x``.

    Args:
        x: signal, shape (n,).
        t: time stamps (s), shape (n,); None means the sample index.
        order: polynomial order p >= 0 (0 removes the mean, 1 a line, ...).
        mask: optional boolean (n,), True for samples to leave out of the fit (e.g. flagged
            outliers); the trend and the residual are still returned for every sample.

    Returns:
        :class:`Detrended` (residual, trend, coef, t_ref, t_scale).

    Example:
        >>> import numpy as np
        >>> t = np.linspace(0.0, 10.0, 11)
        >>> d = detrend(3.0 + 2.0 * t, t, order=1)
        >>> bool(np.allclose(d.residual, 0.0, atol=1e-12)), np.round(d.coef, 12).tolist()
        (True, [13.0, 10.0])
    """
    x = as_1d(x, "x")
    t = np.arange(x.size, dtype=float) if t is None else as_1d(t, "t")
    same_length(x=x, t=t)
    order = check_positive_int(order, "order", minimum=0)
    use = np.ones(x.size, bool) if mask is None else ~np.asarray(mask, dtype=bool)
    same_length(x=x, mask=use)
    if int(use.sum()) < order + 1:
        raise TooShortError(f"a polynomial of order {order} needs at least {order + 1} "
                            f"samples to fit, {int(use.sum())} are usable", column="x",
                            fix="lower the order or pass a longer record")
    t_ref = 0.5 * (t.max() + t.min())
    t_scale = 0.5 * (t.max() - t.min()) or 1.0  # a single time stamp: any scale will do
    u = (t - t_ref) / t_scale
    basis = legendre.legvander(u, order)  # (n, p+1), columns P_0(u) ... P_p(u)
    leg_coef, *_ = np.linalg.lstsq(basis[use], x[use], rcond=None)
    trend = basis @ leg_coef
    coef = legendre.leg2poly(leg_coef)
    coef = np.pad(coef, (0, order + 1 - coef.size))  # leg2poly trims trailing zeros
    return Detrended(x - trend, trend, coef, float(t_ref), float(t_scale))
