"""Maximum-likelihood noise hyperparameters of :mod:`fogbayes.inference.noise_ssm`, one or many fits.

The profile likelihood is maximised over theta (log flicker, log walk, Markov log variances and
time constants) by L-BFGS-B within :func:`~fogbayes.inference.noise_ssm.bounds`, from a small grid
of starts (up to ``n_starts`` regions; it is often bimodal). :func:`fit_noise_many` fits problems
sharing a block grid (:func:`fogbayes.inference.lbfgsb.minimize_one_by_one`); :func:`fit_noise`
is its one-problem case.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from ..support.threads import thread_map
from .lbfgsb import minimize_one_by_one
from .noise_kalman import negloglik
from .noise_ssm import NoiseSpec, bounds, gls

class NoiseFit(NamedTuple):
    """Maximum-likelihood noise fit: spec, theta (unconstrained), the GLS at theta, p."""

    spec: NoiseSpec
    theta: np.ndarray
    loglik: float
    beta: np.ndarray
    cov_beta: np.ndarray
    sigma2: float
    converged: bool
    n_params: int


def _starts(spec: NoiseSpec, theta0) -> np.ndarray:
    """A small grid of starting points (the likelihood can have several modes)."""
    if theta0 is not None:
        return np.atleast_2d(np.asarray(theta0, float))
    grid = []
    for lf in (-6.0, -2.0, 1.0):
        for lrw in (-14.0, -8.0, -3.0):
            row = []
            if spec.bank_taus:
                row.append(lf)
            if spec.random_walk:
                row.append(lrw)
            for j in range(spec.n_markov):
                row.append(-1.0)
            for j in range(spec.n_markov):
                row.append(math.log(max(30.0 * spec.dt * 4 ** j, spec.dt)))
            grid.append(row)
    g = np.unique(np.asarray(grid, float), axis=0)
    return g


def _diverse(starts: np.ndarray, vals: np.ndarray, k: int, gap: float = 3.0) -> list[np.ndarray]:
    """Up to k starts, best first, each differing by > ``gap`` (log units) from those taken."""
    out: list[np.ndarray] = []
    for i in np.argsort(vals):
        if not np.isfinite(vals[i]):
            break
        if all(np.max(np.abs(starts[i] - o)) > gap for o in out):
            out.append(starts[i])
        if len(out) == k:
            break
    return out or [starts[0]]


def _objective(spec: NoiseSpec, problems: list[tuple], mask, w):
    """``batch(rows, thetas)`` of :func:`.lbfgsb.minimize_one_by_one`: row i is ``thetas[i]`` on
    ``problems[rows[i]]`` = (y, X), each row by :func:`.noise_kalman.negloglik`."""
    def batch(rows: np.ndarray, thetas: np.ndarray):
        out = [negloglik(spec, th, *problems[int(r)], mask, w) for r, th in zip(rows, thetas)]
        return np.array([v for v, _ in out]), np.array([g for _, g in out])

    return batch


def fit_noise_many(spec: NoiseSpec, ys, Xs, mask=None, w=None, *, theta0=None,
                   extra_starts=None, maxiter: int = 200, n_starts: int = 3) -> list[NoiseFit]:
    """:func:`fit_noise` of every problem ``(ys[k], Xs[k])`` on one block grid (``mask``, ``w``).

    ``theta0`` / ``extra_starts``: None, or one entry per problem (each None or as in
    :func:`fit_noise`); each problem keeps the best of its starts.
    """
    ys = [np.asarray(y, float) for y in ys]
    Xs = [np.asarray(X, float) for X in Xs]
    K = len(ys)
    n = ys[0].size
    mask = np.ones(n) if mask is None else np.asarray(mask, float)
    w = np.ones(n) if w is None else np.asarray(w, float)
    theta0 = [None] * K if theta0 is None else list(theta0)
    extra_starts = [None] * K if extra_starts is None else list(extra_starts)
    if spec.n_theta == 0:
        out = []
        for y, X in zip(ys, Xs):
            r = gls(spec, np.zeros(0), y, X, mask, w)
            out.append(NoiseFit(spec, np.zeros(0), r.loglik, r.beta, r.cov_beta, r.sigma2,
                                True, int(X.shape[1])))
        return out
    problems = list(zip(ys, Xs))
    lo, hi = np.array(bounds(spec)).T
    owner, x0s = [], []
    for k, (y, X) in enumerate(problems):
        starts = _starts(spec, theta0[k])
        if extra_starts[k] is not None:
            starts = np.vstack([starts, np.atleast_2d(extra_starts[k])])
        starts = np.clip(starts, lo, hi)
        vals = np.array(thread_map(
            lambda th: negloglik(spec, th, y, X, mask, w, grad=False)[0], starts))
        vals = np.where(np.isfinite(vals), vals, np.inf)
        for x0 in _diverse(starts, vals, n_starts):
            owner.append(k)
            x0s.append(x0)
    owner = np.asarray(owner)
    runs = minimize_one_by_one(_objective(spec, [problems[k] for k in owner], mask, w), x0s,
                               bounds(spec), maxiter=maxiter)
    out = []
    for k in range(K):
        best = min((runs[i] for i in np.flatnonzero(owner == k)), key=lambda r: r.fun)
        theta = np.asarray(best.x)
        r = gls(spec, theta, ys[k], Xs[k], mask, w)
        out.append(NoiseFit(spec, theta, r.loglik, r.beta, r.cov_beta, r.sigma2,
                            bool(np.isfinite(best.fun)), int(Xs[k].shape[1])))
    return out


def fit_noise(spec: NoiseSpec, y, X, mask=None, w=None, *, theta0=None,
              extra_starts=None, maxiter: int = 200, n_starts: int = 3) -> NoiseFit:
    """Maximum-likelihood noise hyperparameters with beta and s2 profiled out (L-BFGS-B).

    Args:
        spec: noise structure; y (n,) block means; X (n, p) design (centred/scaled).
        mask: (n,) 1 observed / 0 missing block; w: (n,) white-variance weights.
        theta0: start (skips the start grid); extra_starts: more candidate starts.
    """
    return fit_noise_many(spec, [y], [X], mask, w, theta0=[theta0],
                          extra_starts=[extra_starts], maxiter=maxiter, n_starts=n_starts)[0]
