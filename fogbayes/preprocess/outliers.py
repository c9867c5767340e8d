"""Outlier flags: the iterated 3-sigma (Pauta) rule of paper 004, Hampel and global MAD.

Flags only (a boolean mask as long as the input). Pauta (paper 004 sec. 2.2): flag
|x_i - mean| > 3 s (s with n - 1) and repeat on the unflagged samples until nothing new
(converges to c ~ 2.95, ~0.32 % of Gaussian data; ``max_iter=1`` one pass). Trends: remove
with ``detrend_order`` or ``smooth_window``, or use Hampel.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

from ..errors import ArgumentError, TooShortError
from ._checks import as_1d, check_positive_int, same_length
from .detrend import detrend

#: 1 / Phi^-1(3/4): makes the median absolute deviation a consistent estimate of sigma
#: for Gaussian data.
MAD_TO_SIGMA = 1.482602218505602


class OutlierFlags(NamedTuple):
    """Outlier flags and how they were found.

    mask: bool (n,), True where a sample is an outlier.
    count: number of flagged samples.
    threshold: the final |residual| limit: a float (Pauta, MAD) or a per-sample array
        (Hampel), in the unit of the input.
    iterations: passes made (Pauta; 1 for the one-shot rules).
    method: "pauta", "hampel" or "mad".
    """

    mask: np.ndarray
    count: int
    threshold: float | np.ndarray
    iterations: int
    method: str


def _check_n_sigma(n_sigma: float) -> float:
    if not np.isfinite(n_sigma) or n_sigma <= 0:
        raise ArgumentError(f"n_sigma must be positive, got {n_sigma!r}", column="n_sigma",
                            fix="pass n_sigma=3.0 (the Pauta rule)")
    return float(n_sigma)


def pauta_flags(x, *, n_sigma: float = 3.0, max_iter: int = 100, t=None,
                detrend_order: int | None = None,
                smooth_window: int | None = None, mask=None) -> OutlierFlags:
    """Iterated n-sigma (Pauta) rule on residuals (paper 004).

    Each pass: ``r`` = residual of the samples not yet flagged (``x``, or ``x`` minus a
    polynomial trend refitted on them, or ``x`` minus a running median), ``m`` and ``s``
    their mean and standard deviation (n - 1); flag ``|r_i - m| > n_sigma * s``. Stop when
    a pass flags nothing new or after ``max_iter`` passes. Flags accumulate.

    Args:
        x: signal, shape (n,).
        n_sigma: the multiple of ``s`` (3 in the paper).
        max_iter: at most this many passes (1 = the one-pass 3-sigma rule).
        t: time stamps for ``detrend_order`` (default: the sample index).
        detrend_order: remove a polynomial trend of this order in time first.
        smooth_window: remove a running median over this many samples (odd) first.
        mask: bool (n,), samples flagged beforehand (e.g. :func:`gross_error_flags`): left
            out of every statistic and flagged in the result; their values are not used
            (they may be NaN or infinite).

    Example:
        >>> import numpy as np
        >>> x = np.random.default_rng(0).normal(size=1000); x[500] += 10.0
        >>> f = pauta_flags(x)
        >>> bool(f.mask[500]), f.method
        (True, 'pauta')
    """
    pre = None
    if mask is not None:
        pre = np.asarray(mask, dtype=bool)
        xa = np.asarray(x, dtype=float)
        if pre.shape != xa.shape:
            raise ArgumentError(f"mask has shape {pre.shape} but x has {xa.shape}",
                                column="mask", fix="pass one flag per sample")
        if pre.any():  # stand-ins, never used in a statistic (keeps as_1d's checks)
            fill = np.median(xa[~pre]) if (~pre).any() else 0.0
            x = np.where(pre, fill, xa)
    x = as_1d(x, "x")
    n_sigma = _check_n_sigma(n_sigma)
    max_iter = check_positive_int(max_iter, "max_iter")
    if x.size < 3:
        raise TooShortError(f"the 3-sigma rule needs at least 3 samples, got {x.size}",
                            column="x", fix="pass a longer record")
    if detrend_order is not None and smooth_window is not None:
        raise ArgumentError("pass detrend_order or smooth_window, not both", column="x",
                            fix="choose one way of removing the trend")
    if t is not None:
        same_length(x=x, t=as_1d(t, "t"))
    base = x
    if smooth_window is not None:
        w = _odd_window(smooth_window, x.size, "smooth_window")
        from scipy.ndimage import median_filter  # (0.2 s to import: only when used)

        base = x - median_filter(x, size=w, mode="nearest")
    flagged = np.zeros(x.size, bool) if pre is None else pre.copy()
    threshold, it = np.inf, 0
    for it in range(1, max_iter + 1):
        keep = ~flagged
        if keep.sum() < 3:
            break
        r = base if detrend_order is None else detrend(x, t, detrend_order, mask=flagged).residual
        m, sd = _mean_std(r[keep])
        threshold = n_sigma * sd
        new = keep & (np.abs(r - m) > threshold)
        if not new.any():
            break
        flagged |= new
    return OutlierFlags(flagged, int(flagged.sum()), float(threshold), it, "pauta")


def _mean_std(r: np.ndarray) -> tuple[float, float]:
    """Mean and sample standard deviation (n - 1), without overflow: values near the
    float64 limit (a 1e308 cell) would make the sum of squares infinite and hide them."""
    with np.errstate(over="ignore", invalid="ignore"):
        m, sd = r.mean(), r.std(ddof=1)
    if np.isfinite(m) and np.isfinite(sd):
        return m, sd
    k = float(np.max(np.abs(r)))
    u = r / k
    return k * u.mean(), k * u.std(ddof=1)


#: Robust sigmas beyond which a value is a gross error (see :func:`gross_error_flags`).
GROSS_SIGMAS = 1e3


def gross_error_flags(x, *, n_sigma: float = GROSS_SIGMAS,
                      limit: float | None = None) -> OutlierFlags:
    """Gross errors: values no statistic should see (a 1e308 cell, NaN, infinity).

    Flags ``x_i`` when it is not finite, when ``|x_i| > limit`` (a non-physical magnitude,
    e.g. 1e9 deg/h for a gyro rate), or when ``|x_i - median| > n_sigma * s`` with the
    robust scale ``s = max(1.4826 MAD, (q95 - q05) / 3.29)`` of the finite values (both
    equal sigma for Gaussian data; the 90 % range keeps ``s`` honest when more than half
    of the values are equal, e.g. quantised outputs, and grows with any real drift, so
    that only values ~1e3 times further out than the data's own spread are flagged; when
    ``s`` is 0 only the first two rules apply). Unlike :func:`pauta_flags`, the input may
    hold NaN and infinity. Use it before a least-squares fit or a 3-sigma rule (pass the
    mask on as ``pauta_flags(..., mask=)``): one 1e308 cell makes the variance infinite
    and ruins both.
    """
    a = np.asarray(x, dtype=float)
    if a.ndim != 1:
        raise ArgumentError(f"x must be one-dimensional, got shape {a.shape}", column="x",
                            fix="pass a single column")
    n_sigma = _check_n_sigma(n_sigma)
    mask = ~np.isfinite(a)
    if limit is not None:
        with np.errstate(invalid="ignore"):
            mask |= np.abs(a) > float(limit)
    threshold = np.inf
    ok = ~mask
    if ok.sum() >= 3:
        v = a[ok]
        med = np.median(v)
        with np.errstate(over="ignore"):
            dev = np.abs(v - med)
        q05, q95 = np.quantile(v, [0.05, 0.95])
        with np.errstate(over="ignore", invalid="ignore"):
            s = max(MAD_TO_SIGMA * float(np.median(dev)), float(q95 - q05) / 3.289707253902945)
        if np.isfinite(s) and s > 0:
            threshold = n_sigma * s
            mask[ok] = dev > threshold
    return OutlierFlags(mask, int(mask.sum()), float(threshold), 1, "gross")


def _odd_window(window: int, n: int, name: str) -> int:
    w = check_positive_int(window, name, minimum=3)
    if w % 2 == 0:
        raise ArgumentError(f"{name} must be odd (centred on the sample), got {w}", column=name,
                            fix=f"pass {name}={w + 1}")
    if w > n:
        raise TooShortError(f"{name}={w} samples is longer than the record ({n} samples)",
                            column=name, fix=f"use {name} <= {n - (1 - n % 2)} or a longer record")
    return w


def hampel_flags(x, *, window: int, n_sigma: float = 3.0, min_scale: float = 0.0) -> OutlierFlags:
    """Hampel filter: flag samples far from the median of their window, in MAD units.

    .. math::

        m_i = \\mathrm{median}(x_W), \\quad s_i = 1.4826\\,\\mathrm{median}(|x_W - m_i|),
        \\quad \\text{flag } |x_i - m_i| > n_\\sigma \\max(s_i, \\text{min\\_scale})

    where ``W`` is the ``window`` samples centred on ``i``, shifted inside the record near
    its ends (the first and last ``window // 2`` samples share the edge window). Median and
    MAD ignore a few spikes and follow a slow trend, so no detrending is needed.

    Args:
        x: signal, shape (n,).
        window: odd number of samples, >= 3 and <= n.
        n_sigma: the multiple of the robust sigma.
        min_scale: floor on ``s_i`` (quantised outputs can have MAD = 0 over a window).
    """
    x = as_1d(x, "x")
    n_sigma = _check_n_sigma(n_sigma)
    w = _odd_window(window, x.size, "window")
    starts = np.clip(np.arange(x.size) - w // 2, 0, x.size - w)
    views = sliding_window_view(x, w)
    med = np.empty(x.size)
    mad = np.empty(x.size)
    chunk = max(1, 4_000_000 // w)  # bound the gathered (chunk, w) copy to ~32 MB
    h = w // 2  # w is odd: the median is the middle order statistic
    for a in range(0, x.size, chunk):
        win = views[starts[a:a + chunk]]  # fancy indexing copies, so partition in place
        win.partition(h, axis=1)  # ~8x faster than np.median on many short rows
        med[a:a + chunk] = win[:, h]
        dev = np.abs(win - win[:, h:h + 1])
        dev.partition(h, axis=1)
        mad[a:a + chunk] = dev[:, h]
    threshold = n_sigma * np.maximum(MAD_TO_SIGMA * mad, float(min_scale))
    mask = np.abs(x - med) > threshold
    return OutlierFlags(mask, int(mask.sum()), threshold, 1, "hampel")


def mad_flags(x, *, n_sigma: float = 3.0, t=None, detrend_order: int | None = None) -> OutlierFlags:
    """Global robust rule: flag ``|r_i - median(r)| > n_sigma * 1.4826 * MAD(r)``.

    ``r`` is ``x``, or ``x`` minus a least-squares polynomial trend of ``detrend_order`` in
    ``t``. One pass: the median and MAD are hardly moved by the outliers themselves.
    """
    x = as_1d(x, "x")
    n_sigma = _check_n_sigma(n_sigma)
    if x.size < 3:
        raise TooShortError(f"the MAD rule needs at least 3 samples, got {x.size}", column="x",
                            fix="pass a longer record")
    r = x if detrend_order is None else detrend(x, t, detrend_order).residual
    med = np.median(r)
    threshold = n_sigma * MAD_TO_SIGMA * float(np.median(np.abs(r - med)))
    mask = np.abs(r - med) > threshold
    return OutlierFlags(mask, int(mask.sum()), threshold, 1, "mad")


def flag_outliers(rec, method: str = "pauta", *, unit: str = "deg/h", n_sigma: float = 3.0,
                  window_s: float | None = None, detrend_order: int | None = None,
                  smooth_s: float | None = None, max_iter: int = 100) -> OutlierFlags:
    """Flag outliers in a Recording's rate (``rec.rate(unit)``); nothing is removed.

    Args:
        rec: a :class:`fogbayes.data.Recording`.
        method: "pauta" (iterated 3-sigma, paper 004), "hampel" (rolling median/MAD over
            ``window_s``) or "mad" (global median/MAD).
        unit: rate unit the rule works in (flags do not depend on it for rate units).
        window_s: Hampel window in seconds (required for "hampel"); converted to the
            nearest odd number of samples at ``rec.sample_rate``.
        detrend_order: remove a polynomial trend in time first ("pauta", "mad").
        smooth_s: remove a running median over this many seconds first ("pauta").
        max_iter: Pauta passes.
    """
    x = rec.rate(unit)
    if method == "pauta":
        sw = None if smooth_s is None else _seconds_to_odd(smooth_s, rec, "smooth_s")
        return pauta_flags(x, n_sigma=n_sigma, max_iter=max_iter, t=rec.time,
                           detrend_order=detrend_order, smooth_window=sw)
    if method == "hampel":
        if window_s is None:
            raise ArgumentError("the Hampel filter needs a window", column="window_s",
                                fix="pass window_s (seconds), e.g. window_s=10.0")
        return hampel_flags(x, window=_seconds_to_odd(window_s, rec, "window_s"), n_sigma=n_sigma)
    if method == "mad":
        return mad_flags(x, n_sigma=n_sigma, t=rec.time, detrend_order=detrend_order)
    raise ArgumentError(f"unknown outlier method '{method}'", column="method",
                        fix="use 'pauta', 'hampel' or 'mad'")


def _seconds_to_odd(seconds: float, rec, name: str) -> int:
    """Seconds to the nearest odd number of samples (>= 3)."""
    w = int(round(float(seconds) * rec.sample_rate))
    w = max(3, w + 1 - w % 2)
    if w > rec.n:
        raise TooShortError(f"{name}={seconds:g} s is longer than the record "
                            f"({rec.n} samples)", file=rec.meta.source, column=name,
                            fix=f"use a shorter {name} or a longer record")
    return w
