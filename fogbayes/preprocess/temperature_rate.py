"""Temperature rate dT/dt (deg C/s) from a smoothed temperature, one value per sample.

``"difference"`` (paper 004 sec. 2.2): block means over ``window_s`` (:mod:`.blocks`),
dT = (T_{b+1} - T_b) / (t_{b+1} - t_b); ``align="interp"`` at midpoints, linearly interpolated,
``"hold"`` backward difference (causal). ``"savgol"``: slope of an order-``polyorder`` least-squares
fit to the ``w`` samples around each (actual times; scipy's ``savgol_filter(mode="interp")`` on
an exact grid), per run. Too-short runs: their least-squares slope.
"""

from __future__ import annotations

import os

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

from ..errors import ArgumentError, NonFiniteError, ShapeError
from ._checks import (GAP_FACTOR, as_1d, check_positive_int, check_time, check_window, same_length,
                      segment_bounds)
from .blocks import block_index, group_mean


def temperature_rate(time, temperature, *, method: str = "difference", window_s: float = 10.0,
                     polyorder: int = 2, align: str = "interp",
                     gap_factor: float = GAP_FACTOR) -> np.ndarray:
    """dT/dt in deg C/s at every sample (see the module doc for the two methods).

    Args:
        time: (n,) s, strictly increasing; gaps allowed.
        temperature: (n,) deg C, or (sensors, n) for several sensors sampled at ``time``
            (one 2-D filter call on an exact grid: how ``fogbayes batch`` does a fleet).
        method: "difference" (paper 004) or "savgol".
        window_s: smoothing window (s): block length ("difference", needs two blocks in the
            record) or Savitzky-Golay window ("savgol").
        polyorder: Savitzky-Golay polynomial order (>= 1).
        align: "interp" or "hold" ("difference" only).

    Example:
        >>> import numpy as np
        >>> t = np.arange(100.0)
        >>> r = temperature_rate(t, 20.0 + 0.01 * t, window_s=10.0)
        >>> bool(np.allclose(r, 0.01, rtol=1e-12))
        True
    """
    t = check_time(time)
    T, one = _as_rows(temperature, t.size)
    if method == "difference":
        if align not in ("interp", "hold"):
            raise ArgumentError(f"align must be 'interp' or 'hold', got {align!r}",
                                column="align", fix="pass align='interp' or align='hold'")
        check_window(window_s, t, n_blocks=2)
        out = np.stack([_difference(t, row, window_s, align, gap_factor) for row in T])
        return out[0] if one else out
    if method == "savgol":
        check_window(window_s, t)
        p = check_positive_int(polyorder, "polyorder", minimum=1)
        out = _savgol(t, T, window_s, p, gap_factor)
        return out[0] if one else out
    raise ArgumentError(f"unknown temperature-rate method '{method}'", column="method",
                        fix="use method='difference' or method='savgol'")


def _as_rows(temperature, n: int) -> tuple[np.ndarray, bool]:
    """Temperatures as (sensors, n) finite rows, and whether a single (n,) vector was given."""
    a = np.asarray(temperature, dtype=float)
    if a.ndim == 1:
        as_1d(a, "temperature")
        same_length(time=np.empty(n), temperature=a)
        return a[None, :], True
    if a.ndim != 2 or a.shape[1] != n:
        raise ShapeError(f"temperature has shape {a.shape}, time has {n} samples",
                         column="temperature",
                         fix="pass (n,) or (sensors, n): one row per sensor, one column per sample")
    bad = np.argwhere(~np.isfinite(a))
    if bad.size:
        raise NonFiniteError(f"sensor {int(bad[0][0])}: {len(bad)} value(s) are NaN or infinite",
                             column="temperature", row=int(bad[0][1]),
                             fix="remove or repair those samples first")
    return a, False


def temperature_rate_per_min(time, temperature, **options) -> np.ndarray:
    """:func:`temperature_rate` in deg C/min (the unit of chamber ramp settings)."""
    return 60.0 * temperature_rate(time, temperature, **options)


def ls_slope(t: np.ndarray, y: np.ndarray) -> float:
    """Least-squares slope of y on t (0 for fewer than two samples)."""
    if t.size < 2:
        return 0.0
    tc = t - t.mean()
    return float(np.dot(tc, y - y.mean()) / np.dot(tc, tc))


def rates_from_means(b_seg, b_time, b_mean, q_seg, q_time, q_block, align, fallback):
    """Differences of consecutive block means, mapped onto query points.

    b_*: per block (sorted): run, mean time, mean temperature. q_*: per query point: run,
    time and block number (for "hold"). ``fallback(run)`` gives the rate of a run with a
    single block.
    """
    out = np.empty(q_time.size)
    for s in np.unique(q_seg):
        qs = q_seg == s
        bs = np.flatnonzero(b_seg == s)
        if bs.size < 2:
            out[qs] = fallback(s)
            continue
        tb, Tb = b_time[bs], b_mean[bs]
        r = np.diff(Tb) / np.diff(tb)  # rate between blocks j and j+1
        if align == "interp":
            out[qs] = np.interp(q_time[qs], 0.5 * (tb[1:] + tb[:-1]), r)
        else:  # backward difference held over the block; the run's first block looks forward
            j = q_block[qs] - bs[0]
            out[qs] = r[np.maximum(j - 1, 0)]
    return out


def _difference(t, T, window_s, align, gap_factor):
    bi = block_index(t, window_s, partial="keep", gap_factor=gap_factor)
    tm, Tm, _ = group_mean(bi.block, bi.start.size, t, T[:, None])
    q_seg = bi.segment[bi.block]

    def fallback(s):
        idx = q_seg == s
        return ls_slope(t[idx], T[idx])

    return rates_from_means(bi.segment, tm, Tm[:, 0], q_seg, t, bi.block, align, fallback)


def _savgol(t, T, window_s, p, gap_factor):
    bounds = segment_bounds(t, gap_factor)
    dt_all = float(np.median(np.diff(t)))
    w = int(round(window_s / dt_all))
    w = max(w + 1 - w % 2, p + 1 + (p + 1) % 2, 3)  # odd, and at least p + 1 samples
    out = np.empty(T.shape)  # (sensors, n)
    for a, b in zip(bounds[:-1], bounds[1:]):
        ts, Ts = t[a:b], T[:, a:b]
        if ts.size < w:
            out[:, a:b] = [_whole_run_slope(ts, row, p) for row in Ts]
            continue
        d = np.diff(ts)
        if np.ptp(d) <= 1e-9 * d.mean():  # exact grid: one filter call for every sensor
            # (one sensor: its 1-D row, the exact operations of the streaming path)
            out[:, a:b] = savgol_slope_grid(Ts if len(Ts) > 1 else Ts[0], w, p, float(d.mean()))
        else:
            out[:, a:b] = [local_poly_slope(ts, row, w, p) for row in Ts]
    return out


def savgol_slope_kernel(w: int, p: int, delta: float) -> np.ndarray:
    """Convolution kernel of the Savitzky-Golay first derivative at a window's centre
    (``scipy.signal.savgol_coeffs(w, p, deriv=1, delta=delta, use="conv")``): row 1 of the
    least-squares inverse of the window's Vandermonde matrix, reversed for convolution."""
    h = w // 2
    x = np.arange(-h, h + 1, dtype=float) / h  # scaled: well conditioned for any w
    A = np.vander(x, p + 1, increasing=True)
    return (np.linalg.pinv(A)[1] / (h * delta))[::-1]


def _fft_valid(y: np.ndarray, kernel: np.ndarray) -> np.ndarray:
    """``fftconvolve(y, kernel, mode="valid")`` along the last axis with NumPy's FFT."""
    n, w = y.shape[-1], kernel.size
    size = 1 << int(np.ceil(np.log2(n + w - 1)))
    full = np.fft.irfft(np.fft.rfft(y, size, axis=-1) * np.fft.rfft(kernel, size), size,
                        axis=-1)
    return full[..., w - 1:n]


def savgol_slope_grid(y: np.ndarray, w: int, p: int, delta: float,
                      direct_max: int = 501) -> np.ndarray:
    """Savitzky-Golay derivative on an exact grid, as ``scipy.signal.savgol_filter(y, w, p,
    deriv=1, delta=delta, mode="interp")`` (same numbers to ~1e-12 of the variation).

    ``y``: (n,) or (rows, n), filtered along its last axis. The interior is a convolution
    with the centre kernel (direct for one row and windows up to ``direct_max`` samples,
    else by FFT, O(n log n): a 60 s window at 200 Hz is 12 001 samples); each edge half
    window takes the derivative of the order-p polynomial fitted to the first/last ``w``
    samples, as scipy's ``mode="interp"``. On the FFT path the mean is removed first: it does
    not change a derivative and keeps rounding relative to the variation of ``y``, not to its
    level; the direct path uses the samples as they are, so each value is independent of the
    rest of the array (bit-identical in the streaming path's chunks).
    NumPy only: ``scipy.signal`` costs ~0.9 s to import, most of a ``fogbayes fit`` call.
    """
    n, h = y.shape[-1], w // 2
    out = np.empty(y.shape)
    kernel = savgol_slope_kernel(w, p, delta)
    if w <= direct_max and y.ndim == 1:
        # direct sums of the samples themselves: a sample's value does not depend on the
        # rest of the array (the streaming path's chunks give the same bits)
        y0 = y
        out[h:n - h] = np.convolve(y0, kernel, mode="valid")
    else:
        y0 = y - y.mean(axis=-1, keepdims=True)
        out[..., h:n - h] = _fft_valid(y0, kernel)
    u = (np.arange(w) - h) / h  # scaled positions in an edge window
    poly = np.polynomial.polynomial
    for win, pos in ((slice(0, w), slice(0, h)), (slice(n - w, n), slice(n - h, n))):
        d = poly.polyder(poly.polyfit(u, y0[..., win].T, p))  # (p, rows) or (p,)
        at = u[:h] if pos.start == 0 else u[w - h:]
        out[..., pos] = poly.polyval(at, d) / (h * delta)
    return out


def _whole_run_slope(ts, Ts, p):
    """Derivative of one polynomial fitted to a whole (short) run."""
    if ts.size < 2:
        return np.zeros(ts.size)
    order = min(p, ts.size - 1)
    c, h = ts.mean(), max(np.ptp(ts) / 2, 1e-300)
    coef = np.polynomial.polynomial.polyfit((ts - c) / h, Ts, order)
    poly = np.polynomial.polynomial
    return poly.polyval((ts - c) / h, poly.polyder(coef)) / h


def local_poly_slope(t: np.ndarray, y: np.ndarray, w: int, p: int) -> np.ndarray:
    """Slope at each t_i of the order-p least-squares polynomial through its w-sample window.

    Times are centred on t_i and scaled by the window's reach (u in [-1, 1]) before the
    normal equations sum_j u_j^(a+b) c_b = sum_j u_j^a (y_j - y_i) are formed, which keeps
    them well conditioned for small p. Cost O(n w p), in chunks of bounded memory.
    """
    n = t.size
    starts = np.clip(np.arange(n) - w // 2, 0, n - w)
    tv, yv = sliding_window_view(t, w), sliding_window_view(y, w)
    hankel = np.add.outer(np.arange(p + 1), np.arange(p + 1))
    out = np.empty(n)
    chunk = max(1, 4_000_000 // w)
    for a in range(0, n, chunk):
        idx = np.arange(a, min(a + chunk, n))
        tt = tv[starts[idx]] - t[idx, None]
        reach = np.abs(tt).max(axis=1)
        u = tt / reach[:, None]
        dy = yv[starts[idx]] - y[idx, None]
        moments = np.empty((idx.size, 2 * p + 1))
        rhs = np.empty((idx.size, p + 1))
        uk = np.ones_like(u)
        for k in range(2 * p + 1):
            moments[:, k] = uk.sum(axis=1)
            if k <= p:
                rhs[:, k] = (uk * dy).sum(axis=1)
            if k < 2 * p:
                uk *= u
        coef = np.linalg.solve(moments[:, hankel], rhs[..., None])[..., 0]
        out[idx] = coef[:, 1] / reach
    return out
