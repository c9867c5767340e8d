"""PSIS-LOO, WAIC and PSIS weights of a pointwise log-likelihood of independent draws.

ll (S draws, n observations). WAIC: lppd_i = log mean_s exp(ll_si), v_i = var_s ll_si,
elpd_i = lppd_i - v_i (Watanabe 2010). PSIS (Vehtari, Gelman & Gabry 2017; Vehtari et al.
2024): of raw log ratios r_i (-ll_i for LOO), the largest M = ceil(min(S/5, 3 sqrt(S/reff)))
are replaced by the expected order statistics of a generalised Pareto fitted to them (Zhang
& Stephens 2009, with ArviZ's weakly informative prior on k), capped at the largest raw
ratio; LOO: elpd_i = log sum_s w_si exp(ll_si), w normalised. ``reff``: 1 for independent
draws, for chains :func:`fogbayes.stats.mcmc.relative_efficiency`. The same arithmetic as
``az.loo`` / ``az.waic`` / ``az.psislw`` (ArviZ 0.23, ``scale="log"``; tests/test_psis.py
checks it to 1e-11), vectorised over observations: ArviZ's import (~200 MB, ~1.3 s) and
its per-observation Python loop cost more than the loop's whole ELPD.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from scipy.special import logsumexp as _logsumexp

_TINY_LOG = float(np.log(np.finfo(float).tiny))
_EPS = float(np.finfo(float).eps)


class Criterion(NamedTuple):
    elpd: float
    se: float
    p: float
    pointwise: np.ndarray
    pareto_k: np.ndarray   # per observation (NaN for WAIC)
    warning: bool          # ArviZ's: some k > min(1 - 1/log10 S, 0.7); WAIC: some v_i > 0.4


def waic(ll: np.ndarray) -> Criterion:
    """WAIC (``log`` scale) of ``ll`` (S, n) (module doc)."""
    ll = np.asarray(ll, float)
    lppd = _logsumexp(ll, axis=0) - np.log(ll.shape[0])
    v = np.var(ll, axis=0)
    i = lppd - v
    return Criterion(float(i.sum()), float(np.sqrt(i.size * np.var(i))), float(v.sum()), i,
                     np.full(i.size, np.nan), bool(np.any(v > 0.4)))


def _gpd_fit(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(k, sigma) per row of ``x`` (r, M), each row sorted ascending (Zhang & Stephens 2009;
    ArviZ's ``_gpdfit``, the k prior 10 pseudo-observations at 1/2)."""
    r, n = x.shape
    m = 30 + int(n ** 0.5)
    b = (1.0 - np.sqrt(m / (np.arange(1, m + 1, dtype=float) - 0.5)))[None, :]
    b = b / (3.0 * x[:, int(n / 4 + 0.5) - 1])[:, None] + (1.0 / x[:, -1])[:, None]
    k = np.log1p(-b[:, :, None] * x[:, None, :]).mean(axis=2)
    ls = n * (np.log(-(b / k)) - k - 1.0)
    w = 1.0 / np.exp(ls[:, None, :] - ls[:, :, None]).sum(axis=2)
    w = np.where(w >= 10 * _EPS, w, 0.0)
    w /= w.sum(axis=1, keepdims=True)
    b_post = np.sum(b * w, axis=1)
    k_post = np.log1p(-b_post[:, None] * x).mean(axis=1)
    sigma = -k_post / b_post
    return (n * k_post + 10 * 0.5) / (n + 10), sigma


def _gpd_quantiles(p: np.ndarray, k: np.ndarray, sigma: np.ndarray) -> np.ndarray:
    """Quantiles ``p`` (M,) of generalised Paretos (k, sigma) (r,): (r, M); NaN where sigma <= 0."""
    k, sigma = k[:, None], sigma[:, None]
    small = np.abs(k) < _EPS
    with np.errstate(divide="ignore", invalid="ignore"):
        q = np.where(small, -np.log1p(-p)[None, :],
                     np.expm1(-np.where(small, 1.0, k) * np.log1p(-p)[None, :])
                     / np.where(small, 1.0, k))
    return np.where(sigma > 0, q * sigma, np.nan)


def _smoothed_rows(x: np.ndarray, m_tail: int) -> tuple[np.ndarray, np.ndarray]:
    """Normalised PSIS log weights and k of each row of ``x`` (r, S): log ratios sorted
    ascending, each row's largest 0 (a copy is smoothed)."""
    x = np.array(x, float)
    S = x.shape[1]
    cut = np.maximum(x[:, S - m_tail - 1], _TINY_LOG)
    k = np.full(x.shape[0], np.inf)
    if m_tail > 4:
        tail = np.exp(x[:, S - m_tail:]) - np.exp(cut)[:, None]
        with np.errstate(divide="ignore", invalid="ignore"):
            k, sigma = _gpd_fit(tail)
            fin = np.isfinite(k)
            if fin.any():
                p = (np.arange(m_tail) + 0.5) / m_tail
                sm = np.log(_gpd_quantiles(p, k[fin], sigma[fin]) + np.exp(cut[fin])[:, None])
                rows = x[fin]
                rows[:, S - m_tail:] = sm
                rows[rows > 0] = 0.0
                x[fin] = rows
    return x - _logsumexp(x, axis=1)[:, None], k


def _tail_length(S: int, reff: float = 1.0) -> int:
    return int(np.ceil(min(S / 5.0, 3 * np.sqrt(S / reff))))


def psislw(log_ratios: np.ndarray, reff: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Pareto-smoothed, normalised log importance weights of each row of ``log_ratios``
    (n, S) and each row's Pareto k: ``az.psislw(log_ratios, reff)``; ``reff``, the draws'
    relative efficiency (1 for independent draws), sets the tail's length."""
    lw = np.asarray(log_ratios, float)
    S = lw.shape[1]
    order = np.argsort(lw, axis=1)
    x = np.take_along_axis(lw, order, axis=1)
    x -= x[:, -1:]
    # the tail: every weight above the cut-off, the M-th largest (or exp-underflow) -- the M
    # largest unless ties or underflow make it shorter; those rows go one by one
    m_tail = _tail_length(S, reff)
    cut = np.maximum(x[:, S - m_tail - 1], _TINY_LOG)
    n_tail = np.sum(x > cut[:, None], axis=1)
    w = np.empty_like(x)
    k = np.empty(x.shape[0])
    regular = n_tail == m_tail
    w[regular], k[regular] = _smoothed_rows(x[regular], m_tail)
    for j in np.flatnonzero(~regular):
        wj, kj = _smoothed_rows(x[j][None], int(n_tail[j]))
        w[j], k[j] = wj[0], kj[0]
    out = np.empty_like(w)
    np.put_along_axis(out, order, w, axis=1)
    return out, k


def loo(ll: np.ndarray, reff: float = 1.0) -> Criterion:
    """PSIS-LOO (``log`` scale) of ``ll`` (S, n) (module doc); ``reff`` as in :func:`psislw`
    (for chains, ArviZ takes the mean ESS of the posterior's components over S)."""
    ll = np.asarray(ll, float)
    S = ll.shape[0]
    w, k = psislw(-ll.T, reff)  # rows: observations
    i = _logsumexp(w + ll.T, axis=1)
    lppd = float(np.sum(_logsumexp(ll.T, axis=1) - np.log(S)))
    good_k = min(1 - 1 / np.log10(S), 0.7)
    return Criterion(float(i.sum()), float(np.sqrt(i.size * np.var(i))), lppd - float(i.sum()),
                     i, k, bool(np.any(k > good_k)))
