"""Convergence of MCMC chains without ArviZ: rank-normalised split R-hat, bulk, tail and
mean effective sample sizes (Vehtari, Gelman, Simpson, Carpenter & Buerkner 2021).

The arithmetic of ArviZ 0.23's ``rhat(method="rank")`` and ``ess(method="bulk" | "tail" |
"mean")`` for one scalar quantity, ``ary`` (chains, draws); ``tests/test_mcmc_diagnostics.py``
compares every function with ArviZ. Split chains: each chain's first and last
``draws // 2`` draws. z-scale: ranks (ties averaged) mapped to normal quantiles with Blom's
offset 3/8. ESS: autocovariances by FFT, Geyer's initial positive then monotone sequence.
"""

from __future__ import annotations

import numpy as np
from scipy import fft

from ..support.tails import norm_ppf


def _split(ary: np.ndarray) -> np.ndarray:
    half = ary.shape[1] // 2
    return np.concatenate([ary[:, :half], ary[:, ary.shape[1] - half:]])


def _z_scale(ary: np.ndarray) -> np.ndarray:
    return norm_ppf((_average_ranks(ary.ravel()).reshape(ary.shape) - 0.375)
                    / (ary.size + 0.25))


def _average_ranks(a: np.ndarray) -> np.ndarray:
    """1-based ranks of ``a``, ties given their mean rank (``scipy.stats.rankdata``'s
    "average", by its own algorithm: a stable sort, runs of equal values, their bounds)."""
    order = np.argsort(a, kind="mergesort")
    inverse = np.empty(order.size, np.intp)
    inverse[order] = np.arange(order.size)
    s = a[order]
    new = np.r_[True, s[1:] != s[:-1]]
    run = np.cumsum(new)[inverse]
    bounds = np.r_[np.flatnonzero(new), new.size]
    return 0.5 * (bounds[run] + bounds[run - 1] + 1)


def _rhat(ary: np.ndarray) -> float:
    n = ary.shape[1]
    between = n * np.var(ary.mean(axis=1), ddof=1)
    within = np.mean(np.var(ary, axis=1, ddof=1))
    with np.errstate(invalid="ignore", divide="ignore"):  # constant draws: NaN, as ArviZ
        return float(np.sqrt((between / within + n - 1) / n))


def rhat_rank(ary) -> float:
    """max(split R-hat of the z-scaled draws, of the z-scaled |draw - median|); NaN for
    fewer than 2 chains or 4 draws."""
    ary = np.asarray(ary, float)
    if ary.shape[0] < 2 or ary.shape[1] < 4:
        return float("nan")
    split = _split(ary)
    return max(_rhat(_z_scale(split)), _rhat(_z_scale(np.abs(split - np.median(split)))))


def _autocov(ary: np.ndarray) -> np.ndarray:
    n = ary.shape[1]
    m = fft.next_fast_len(2 * n)
    x = ary - ary.mean(axis=1, keepdims=True)
    f = np.fft.rfft(x, n=m, axis=1)
    return np.fft.irfft(f * np.conjugate(f), n=m, axis=1)[:, :n] / n


def _ess(ary: np.ndarray) -> float:
    ary = np.asarray(ary, float)
    if np.max(ary) - np.min(ary) < np.finfo(float).resolution:
        return float(ary.size)
    n_chain, n_draw = ary.shape
    acov = _autocov(ary)
    mean_var = np.mean(acov[:, 0]) * n_draw / (n_draw - 1.0)
    var_plus = mean_var * (n_draw - 1.0) / n_draw
    if n_chain > 1:
        var_plus += np.var(ary.mean(axis=1), ddof=1)
    rho = np.zeros(n_draw)
    rho_even, rho[0] = 1.0, 1.0
    rho_odd = rho[1] = 1.0 - (mean_var - np.mean(acov[:, 1])) / var_plus
    t = 1  # Geyer's initial positive sequence
    while t < n_draw - 3 and rho_even + rho_odd > 0.0:
        rho_even = 1.0 - (mean_var - np.mean(acov[:, t + 1])) / var_plus
        rho_odd = 1.0 - (mean_var - np.mean(acov[:, t + 2])) / var_plus
        if rho_even + rho_odd >= 0:
            rho[t + 1], rho[t + 2] = rho_even, rho_odd
        t += 2
    max_t = t - 2
    if rho_even > 0:
        rho[max_t + 1] = rho_even
    t = 1  # Geyer's initial monotone sequence
    while t <= max_t - 2:
        if rho[t + 1] + rho[t + 2] > rho[t - 1] + rho[t]:
            rho[t + 1] = rho[t + 2] = (rho[t - 1] + rho[t]) / 2.0
        t += 2
    size = n_chain * n_draw
    tau = -1.0 + 2.0 * np.sum(rho[:max_t + 1]) + np.sum(rho[max_t + 1:max_t + 2])
    tau = max(tau, 1 / np.log10(size))
    return float("nan") if np.isnan(rho).any() else float(size / tau)


def ess_bulk(ary) -> float:
    """ESS of the z-scaled split chains."""
    return _ess(_z_scale(_split(np.asarray(ary, float))))


def ess_tail(ary) -> float:
    """The smaller ESS of the indicators draw <= 5 % and <= 95 % quantile (split chains)."""
    ary = np.asarray(ary, float)
    return min(_ess(_split((ary <= np.quantile(ary, p)).astype(float))) for p in (0.05, 0.95))


def ess_mean(ary) -> float:
    """ESS of the split chains themselves (what ArviZ's LOO takes the efficiency from)."""
    return _ess(_split(np.asarray(ary, float)))


def over_elements(fn, draws) -> np.ndarray:
    """``fn`` of each scalar component of ``draws`` (chains, draws, ...) -> array (...)."""
    draws = np.asarray(draws, float)
    flat = draws.reshape(draws.shape[:2] + (-1,))
    return np.array([fn(flat[:, :, j]) for j in range(flat.shape[2])]).reshape(draws.shape[2:])


def relative_efficiency(draws) -> float:
    """ArviZ's relative efficiency of chains for PSIS-LOO: the mean "mean" ESS of every
    scalar component of ``draws`` (arrays (chains, draws, ...)) over chains x draws; 1 for
    one chain."""
    draws = [np.asarray(d, float) for d in draws]
    chains, n = draws[0].shape[:2]
    if chains == 1:
        return 1.0
    ess = np.concatenate([np.ravel(over_elements(ess_mean, d)) for d in draws])
    return float(ess.mean() / (chains * n))
