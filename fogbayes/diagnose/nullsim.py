"""Null simulations and grid likelihoods under the state-space noise model.

* :func:`simulate` draws noise series from a fitted :class:`~fogbayes.inference.noise_ssm.NoiseSpec`
  (NumPy, every component an independent AR(1)/random walk by ``lfilter``);
* :func:`column_logliks` evaluates the profile log-likelihood of many response columns
  under many hyperparameter vectors in one compiled, vmapped Kalman pass -- the
  ``markov_noise`` screening and its bootstrap use it.
"""

from __future__ import annotations

from functools import partial

import jax
import jax.numpy as jnp
import numpy as np
from jax import lax

from ..inference.noise_ssm import UNROLL, NoiseSpec, system, unpack


def simulate(spec: NoiseSpec, theta, sigma2: float, w, n_sims: int, *, seed: int) -> np.ndarray:
    """Draw (n, n_sims) noise series from the model (state started from its initial law).

    The state is diagonal, so every component is an independent AR(1) (or random walk)
    x_{t+1} = phi x_t + u_t, drawn by ``scipy.signal.lfilter`` over all series at once
    (NumPy: nothing to compile), plus white noise of variance s2 w_t.
    """
    from scipy.signal import lfilter

    sysm = system(spec, unpack(spec, jnp.asarray(theta, dtype=float)))
    phi, q, p0 = (np.asarray(a, dtype=float) for a in sysm)
    w = np.asarray(w, dtype=float)
    n = w.size
    rng = np.random.default_rng(seed)
    out = np.sqrt(w)[:, None] * rng.standard_normal((n, n_sims))
    for j in range(phi.size):
        u = np.sqrt(q[j]) * rng.standard_normal((n, n_sims))
        u[0] = np.sqrt(p0[j]) * rng.standard_normal(n_sims)  # x_0 from the initial law
        # x_t = phi x_{t-1} + u_{t-1} for t >= 1, x_0 = u[0]: filter the shifted innovations
        x = lfilter([1.0], [1.0, -phi[j]], u, axis=0)
        out += x
    return np.sqrt(sigma2) * out


def _column_logliks(phi, q, p0, y_cols, X, mask, w, pad):
    """Profile log-likelihood of each column of y_cols (n, C) regressed on X (n, p)."""
    d, p, C = phi.shape[0], X.shape[1], y_cols.shape[1]
    Y = jnp.concatenate([X, y_cols], axis=1) * mask[:, None]

    def step(carry, inp):
        A, P, Sx, sd, slf = carry
        yt, m, wt = inp
        Pz = P.sum(axis=1)
        F = Pz.sum() + wt
        v = yt - A.sum(axis=0)
        k = Pz / F
        Af = A + m * jnp.outer(k, v)
        Pf = P - m * jnp.outer(k, Pz)
        Pn = phi[:, None] * Pf * phi[None, :] + jnp.diag(q)
        g = m / F
        return (phi[:, None] * Af, 0.5 * (Pn + Pn.T), Sx + g * jnp.outer(v[:p], v),
                sd + g * v * v, slf + m * jnp.log(F)), None

    init = (jnp.zeros((d, p + C)), jnp.diag(p0), jnp.zeros((p, p + C)), jnp.zeros(p + C),
            jnp.zeros(()))
    (_, _, Sx, sd, slf), _ = lax.scan(step, init, (Y, mask, w), unroll=UNROLL)
    Sxx = Sx[:, :p] + jnp.diag(pad)
    Sxy = Sx[:, p:]
    L = jnp.linalg.cholesky(Sxx)
    B = jax.scipy.linalg.cho_solve((L, True), Sxy)
    rss = sd[p:] - jnp.sum(Sxy * B, axis=0)
    nobs = mask.sum()
    return -0.5 * (nobs * jnp.log(2 * jnp.pi * rss / nobs) + slf + nobs)


@partial(jax.jit, static_argnums=0)
def column_logliks(spec: NoiseSpec, thetas, y_cols, X, mask, w, pad):
    """(G, C) profile log-likelihoods of C response columns under G hyperparameter vectors.

    Every column is its own regression on X (beta and s2 profiled per column); used to
    evaluate a grid of noise models on data and simulated series in one compiled call.
    """
    def one(th):
        phi, q, p0 = system(spec, unpack(spec, th))
        return _column_logliks(phi, q, p0, y_cols, X, mask, w, pad)
    return jax.vmap(one)(thetas)
