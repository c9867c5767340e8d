"""Null simulations and grid likelihoods under :mod:`fogbayes.inference.noise_ssm`'s model.

:func:`simulate` draws series from a :class:`~fogbayes.inference.noise_ssm.NoiseSpec` (each
component an AR(1)/walk by ``lfilter``). :func:`column_logliks` gives the profile log-likelihood
of many columns under many hyperparameters: ``noise_ssm.whiten_raw`` then GLS per column,
log L = -1/2 [n log(2 pi RSS / n) + sum m log F + n].
"""

from __future__ import annotations

from functools import partial

import jax
import jax.numpy as jnp
import numpy as np

from ..inference.noise_ssm import NoiseSpec, system, unpack, whiten_raw
from ..support.programs import program

#: Hyperparameter vectors filtered together (bounds memory: batch x n x columns floats).
BATCH = 16


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


def _profile_columns(V, F, mask, p: int, pad):
    """Profile log-likelihood of every response column from innovations V = [V_X, V_Y]."""
    g = mask / F
    VX, VY = V[:, :p], V[:, p:]
    GX = VX * g[:, None]
    Sxx = GX.T @ VX + jnp.diag(pad)
    Sxy = GX.T @ VY
    L = jnp.linalg.cholesky(Sxx)
    B = jax.scipy.linalg.cho_solve((L, True), Sxy)
    R = VY - VX @ B  # RSS from the residuals (noise_ssm's module doc, "Precision")
    rss = jnp.sum(g[:, None] * R * R, axis=0)
    nobs = mask.sum()
    return -0.5 * (nobs * jnp.log(2 * jnp.pi * rss / nobs) + jnp.sum(mask * jnp.log(F)) + nobs)


@partial(program, static_argnums=0)
def column_logliks(spec: NoiseSpec, thetas, y_cols, X, mask, w, pad):
    """(G, C) profile log-likelihoods of C response columns under G hyperparameter vectors.

    Every column is its own regression on X (beta and s2 profiled per column); used to
    evaluate a grid of noise models on data and simulated series in one compiled call.
    """
    p = X.shape[1]
    Y = jnp.concatenate([X, y_cols], axis=1)

    def one(th):
        V, F = whiten_raw(spec, th, Y, mask, w)
        return _profile_columns(V, F, mask, p, pad)
    return jax.lax.map(one, thetas, batch_size=BATCH)
