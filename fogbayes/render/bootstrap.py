"""Intervals for bias stability and its improvement: a circular block bootstrap (NumPy).

Circular block bootstrap (Politis & Romano 1992) of the window means, block length L by
Politis & White (2004) with Patton, Politis & White (2009) (largest over the series, 1 <= L <= n/3);
before and after share the block starts, so the improvement 100 (1 - after / before) is a ratio
of the same draw. Percentile interval at ``level`` (0.9), ``n_boot`` = 2000, seed 0. It assumes
stationary means with dependence shorter than L.
"""

from __future__ import annotations

import math
from typing import NamedTuple, Sequence

import numpy as np

LEVEL = 0.90
N_BOOT = 2000
SEED = 0


class Interval(NamedTuple):
    """A point value and its bootstrap interval at ``level``."""

    value: float
    low: float
    high: float


class StabilityInterval(NamedTuple):
    """Bias stability before and after with intervals, and the improvement in %."""

    window_s: float
    before: Interval
    after: Interval
    improvement_pct: Interval
    n_means: int
    block_length: int
    n_boot: int
    level: float
    seed: int

    def method(self) -> str:
        """One sentence for a footnote: how the intervals were computed."""
        return method_text(self, paired=True)


class StdInterval(NamedTuple):
    """Bias stability of one rate (no compensation) with its interval."""

    window_s: float
    value: Interval
    n_means: int
    block_length: int
    n_boot: int
    level: float
    seed: int

    def method(self) -> str:
        return method_text(self, paired=False)


def method_text(r, *, paired: bool) -> str:
    """The footnote of a report: how an interval of :class:`StabilityInterval` was made."""
    s = (f"{r.level:.0%} intervals from a circular block bootstrap of the {r.n_means} "
         f"consecutive {r.window_s:g} s means (blocks of {r.block_length} means, the length "
         f"chosen from their autocorrelation by the Politis-White rule; {r.n_boot} resamples, "
         f"seed {r.seed}, percentile intervals).")
    if paired:
        s += (" Before and after are resampled with the same blocks, so the improvement "
              "interval keeps their correlation.")
    return s + (" A chi-square interval would assume independent means, which coloured FOG "
                "noise does not give. With a drift over the whole record the interval says "
                "how much the number depends on the stretch of record, not how repeatable a "
                "new test would be.")


def block_length(x: np.ndarray) -> int:
    """Politis-White (2004, corrected 2009) block length for the circular bootstrap of ``x``."""
    x = np.asarray(x, float)
    n = x.size
    if n < 8:
        return 1
    x = x - x.mean()
    var = float(np.dot(x, x)) / n
    if var <= 0.0 or not np.isfinite(var):
        return 1
    kn = max(5, math.ceil(math.sqrt(math.log10(n))))
    m_max = min(n - 1, math.ceil(math.sqrt(n)) + kn)
    # autocovariances R(0..m_max + kn) by FFT
    nfft = 1 << (2 * n - 1).bit_length()
    f = np.fft.rfft(x, nfft)
    acov = np.fft.irfft(f * np.conj(f), nfft)[: min(n, m_max + kn + 1)] / n
    rho = acov / acov[0]
    thresh = 2.0 * math.sqrt(math.log10(n) / n)
    insignificant = np.abs(rho[1:]) < thresh  # insignificant[k-1] is lag k
    m_hat = None
    for m in range(0, m_max + 1):  # smallest m after which kn lags in a row are insignificant
        window = insignificant[m:m + kn]
        if window.size == kn and window.all():
            m_hat = m
            break
    if m_hat is None:
        m_hat = m_max
    big_m = int(min(2 * max(m_hat, 1), m_max))
    k = np.arange(-big_m, big_m + 1)
    t = np.abs(k) / big_m
    lam = np.where(t <= 0.5, 1.0, np.where(t <= 1.0, 2.0 * (1.0 - t), 0.0))
    r = acov[np.abs(k)]
    g = float(np.sum(lam * np.abs(k) * r))
    d = (4.0 / 3.0) * float(np.sum(lam * r)) ** 2
    if d <= 0.0 or g == 0.0:
        return 1
    b = (2.0 * g * g / d) ** (1.0 / 3.0) * n ** (1.0 / 3.0)
    return int(min(max(1, round(b)), max(1, n // 3)))


def std_draws(series: Sequence[np.ndarray], *, length: int, n_boot: int = N_BOOT,
              rng: np.random.Generator | None = None) -> np.ndarray:
    """Circular-block-bootstrap draws of the std (ddof=1) of each series, shape (n_boot, k).

    All series (equal length) are resampled with the same block starts. Each draw costs
    O(n / L): block sums and sums of squares come from cumulative sums.
    """
    rng = np.random.default_rng(SEED) if rng is None else rng
    x = np.atleast_2d(np.asarray(series, float))
    k, n = x.shape
    length = int(max(1, min(length, n)))
    nb = max(1, math.ceil(n / length))
    x = x - x.mean(axis=1, keepdims=True)  # centred: sums of squares lose nothing
    ext = np.concatenate([x, x[:, :length]], axis=1)  # circular
    c1 = np.concatenate([np.zeros((k, 1)), np.cumsum(ext, axis=1)], axis=1)
    c2 = np.concatenate([np.zeros((k, 1)), np.cumsum(ext * ext, axis=1)], axis=1)
    s1 = c1[:, length:length + n] - c1[:, :n]  # (k, n): block sums starting at each i
    s2 = c2[:, length:length + n] - c2[:, :n]
    starts = rng.integers(0, n, size=(n_boot, nb))
    total = nb * length
    out = np.empty((n_boot, k))
    for j in range(k):
        a1 = s1[j][starts].sum(axis=1)
        a2 = s2[j][starts].sum(axis=1)
        out[:, j] = np.sqrt(np.maximum(a2 - a1 * a1 / total, 0.0) / (total - 1))
    return out


def percentile(draws: np.ndarray, level: float = LEVEL) -> tuple[float, float]:
    q = (1.0 - level) / 2.0
    lo, hi = np.quantile(draws, [q, 1.0 - q])
    return float(lo), float(hi)


def std_interval(means: np.ndarray, *, level: float = LEVEL, n_boot: int = N_BOOT,
                 seed: int = SEED, length: int | None = None) -> Interval:
    """Standard deviation of ``means`` with its circular-block-bootstrap interval."""
    means = np.asarray(means, float)
    length = block_length(means) if length is None else length
    d = std_draws([means], length=length, n_boot=n_boot, rng=np.random.default_rng(seed))[:, 0]
    return Interval(float(np.std(means, ddof=1)), *percentile(d, level))


def paired_interval(before_means: np.ndarray, after_means: np.ndarray, *, window_s: float = 1.0,
                    level: float = LEVEL, n_boot: int = N_BOOT, seed: int = SEED,
                    length: int | None = None) -> StabilityInterval:
    """Before/after bias stability from aligned window means, and the improvement in %."""
    b, a = np.asarray(before_means, float), np.asarray(after_means, float)
    if b.shape != a.shape or b.ndim != 1 or b.size < 3:
        raise ValueError("before and after need the same number (>= 3) of window means")
    length = max(block_length(b), block_length(a)) if length is None else int(length)
    d = std_draws([b, a], length=length, n_boot=n_boot, rng=np.random.default_rng(seed))
    sb, sa = float(np.std(b, ddof=1)), float(np.std(a, ddof=1))
    imp = 100.0 * (1.0 - d[:, 1] / d[:, 0])
    return StabilityInterval(
        float(window_s), Interval(sb, *percentile(d[:, 0], level)),
        Interval(sa, *percentile(d[:, 1], level)),
        Interval(100.0 * (sb - sa) / sb if sb > 0 else float("nan"), *percentile(imp, level)),
        int(b.size), int(length), int(n_boot), float(level), int(seed))


def stability_intervals(before: np.ndarray, afters: dict[str, np.ndarray], time: np.ndarray, *,
                        window_s: float = 1.0, keep: np.ndarray | None = None,
                        level: float = LEVEL, n_boot: int = N_BOOT,
                        seed: int = SEED) -> dict[str, StabilityInterval]:
    """Bias stability (deg/h) on ``window_s`` means: ``before`` against each of ``afters``.

    Rates in deg/h on the same ``time``; ``keep`` (bool) leaves samples out of all of them
    (e.g. flagged outliers, as :func:`fogbayes.loop.metrics.stability` does). The point
    values equal :func:`fogbayes.stats.stability.bias_stability`. Every pair uses one block length
    (the largest of all the series) and the same seed, hence the same resampled blocks.
    """
    from ..stats.stability import window_means

    time, before = np.asarray(time, float), np.asarray(before, float)
    afters = {k: np.asarray(v, float) for k, v in afters.items()}
    if keep is not None:
        keep = np.asarray(keep, bool)
        time, before = time[keep], before[keep]
        afters = {k: v[keep] for k, v in afters.items()}
    mb = window_means(time, before, window_s)
    ma = {k: window_means(time, v, window_s) for k, v in afters.items()}
    ok = np.isfinite(mb)
    for v in ma.values():
        ok &= np.isfinite(v)
    mb, ma = mb[ok], {k: v[ok] for k, v in ma.items()}
    length = max([block_length(mb)] + [block_length(v) for v in ma.values()])
    return {k: paired_interval(mb, v, window_s=window_s, level=level, n_boot=n_boot, seed=seed,
                               length=length) for k, v in ma.items()}


def single_stability(rate: np.ndarray, time: np.ndarray, *, window_s: float = 1.0,
                     keep: np.ndarray | None = None, level: float = LEVEL,
                     n_boot: int = N_BOOT, seed: int = SEED) -> StdInterval:
    """Bias stability (deg/h) of one rate on ``window_s`` means, with its interval."""
    from ..stats.stability import window_means

    time, rate = np.asarray(time, float), np.asarray(rate, float)
    if keep is not None:
        keep = np.asarray(keep, bool)
        time, rate = time[keep], rate[keep]
    m = window_means(time, rate, window_s)
    m = m[np.isfinite(m)]
    if m.size < 3:
        raise ValueError(f"bias stability on {window_s:g} s windows needs >= 3 window means")
    length = block_length(m)
    iv = std_interval(m, level=level, n_boot=n_boot, seed=seed, length=length)
    return StdInterval(float(window_s), iv, int(m.size), int(length), int(n_boot), float(level),
                       int(seed))


def stability_interval(before: np.ndarray, after: np.ndarray, time: np.ndarray, *,
                       window_s: float = 1.0, keep: np.ndarray | None = None,
                       level: float = LEVEL, n_boot: int = N_BOOT,
                       seed: int = SEED) -> StabilityInterval:
    """:func:`stability_intervals` for one ``after``."""
    return stability_intervals(before, {"after": after}, time, window_s=window_s, keep=keep,
                               level=level, n_boot=n_boot, seed=seed)["after"]
