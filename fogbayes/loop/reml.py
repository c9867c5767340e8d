"""Restricted (REML) noise hyperparameters for the evidence's null simulations.

log L_R = -1/2 [(n - p) log(2 pi s2_R) + sum_t m_t log F_t + log det S_XX + (n - p)],
s2_R = RSS / (n - p) (Patterson & Thompson 1971; filter of :mod:`fogbayes.inference.noise_ssm`).
ML underestimates slow noise the design absorbs; REML is used only for whitening and
simulating, ML likelihoods for the ratios.
"""

from __future__ import annotations

from functools import partial

import numpy as np

from ..inference import noise_ssm as ns
from ..inference import noise_fit as nfit
from ..inference.lbfgsb import failed_as_large, minimize_one_by_one
from ..inference.noise_kalman import negloglik
from ..support.lazy import lazy_module
from ..support.programs import program
from ..support.threads import thread_map

jax = lazy_module("jax")  # the JAX definition below only: the fits use noise_kalman
jnp = lazy_module("jax.numpy")


@partial(program, static_argnums=0)
def _negreml_and_grad(spec: ns.NoiseSpec, theta, y, X, mask, w, pad):
    """-log L_R and its gradient by JAX autodiff: the definition that
    :func:`fogbayes.inference.noise_kalman.negloglik` (``reml=True``, what the fits call) is
    tested against."""
    def f(th):
        Y = jnp.concatenate([y[:, None], X], axis=1)
        V, F = ns.whiten_raw(spec, th, Y, mask, w)
        g = mask / F
        S = (V * g[:, None]).T @ V
        Sxx = S[1:, 1:] + jnp.diag(pad)
        L = jnp.linalg.cholesky(Sxx)
        beta = jax.scipy.linalg.cho_solve((L, True), S[1:, 0])
        r = V[:, 0] - V[:, 1:] @ beta  # from the residual (noise_ssm's module doc, "Precision")
        rss = jnp.sum(g * r * r)
        n = mask.sum() - (pad.size - pad.sum())
        logdet = 2.0 * jnp.sum(jnp.log(jnp.diag(L)))  # pad columns add log 1 = 0
        return 0.5 * (n * jnp.log(2 * jnp.pi * rss / n) + jnp.sum(mask * jnp.log(F))
                      + logdet + n)
    return jax.value_and_grad(f)(theta)


def _starts(spec: ns.NoiseSpec, theta: np.ndarray) -> np.ndarray:
    """The ML values, and the ML values with the slow variances moved over a small grid.

    ML often puts a variance on its lower bound (the design took all of it); the
    restricted likelihood is flat there, so REML needs starts away from it.
    """
    rows = [np.array(theta, float)]
    n_var = int(bool(spec.bank_taus)) + int(spec.random_walk)
    grid = {0: (-6.0, -2.0, 1.0), 1: (-14.0, -8.0, -3.0)} if n_var == 2 else \
        {0: (-14.0, -8.0, -3.0, 1.0)}
    if n_var == 2:
        for a in grid[0]:
            for b in grid[1]:
                row = np.array(theta, float)
                row[:2] = a, b
                rows.append(row)
    elif n_var == 1:
        for a in grid[0]:
            row = np.array(theta, float)
            row[0] = a
            rows.append(row)
    return np.array(rows)


def reml_theta(nf: nfit.NoiseFit, y, X, mask, w, *, maxiter: int = 200,
               n_starts: int = 2) -> np.ndarray:
    """REML hyperparameters of the model (``nf``: its ML noise fit).

    The objective is evaluated at the ML values and at a small grid of slow-noise
    variances; L-BFGS-B runs from the best ``n_starts`` of them (within the ML bounds).
    """
    spec = nf.spec
    if spec.n_theta == 0:
        return np.zeros(0)
    lo, hi = np.array(ns.bounds(spec)).T

    def batch(rows, thetas):  # one row at a time (the batch interface of lbfgsb)
        v, g = negloglik(spec, thetas[0], y, X, mask, w, reml=True)
        return np.array([v]), np.asarray(g, dtype=float)[None]

    def value(th) -> float:  # the start's objective, a failed point as 1e300
        v, g = batch(None, th[None])
        return failed_as_large(v[0], g[0])[0]

    starts = np.clip(_starts(spec, nf.theta), lo, hi)
    vals = np.array(thread_map(value, starts))
    runs = minimize_one_by_one(batch, [starts[i] for i in np.argsort(vals)[:n_starts]],
                               list(zip(lo, hi)), maxiter=maxiter)
    return np.asarray(min(runs, key=lambda r: r.fun).x)


def with_reml(ctx, fit, cache: dict | None = None):
    """``fit`` (a :class:`~fogbayes.loop.fitting.ModelFit`) with its noise hyperparameters
    replaced by their REML values on the same design; cached per fit in ``cache``."""
    key = ("reml", id(fit.noise))
    if cache is not None and key in cache:
        return cache[key][1]
    th = reml_theta(fit.noise, ctx.y, fit.X, ctx.grid.mask, ctx.grid.w)
    out = fit._replace(noise=fit.noise._replace(theta=th))
    if cache is not None:
        cache[key] = (fit, out)  # keep fit alive so its id is not reused
    return out
