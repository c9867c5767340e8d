"""Null simulations and grid likelihoods under :mod:`fogbayes.inference.noise_ssm`'s model.

:func:`simulate` draws series from a :class:`~fogbayes.inference.noise_ssm.NoiseSpec` (each
component an AR(1) or walk, :func:`fogbayes.support.first_order_filter.ar1_filter`). :func:`column_logliks`
gives the profile log-likelihood of many columns under many hyperparameters: the CPU filter of
:mod:`fogbayes.inference.noise_kalman`, then GLS per column,
log L = -1/2 [n log(2 pi RSS / n) + sum m log F + n].
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import cho_solve

from ..inference.noise_kalman import innovations, system
from ..inference.noise_ssm import NoiseSpec
from ..support.first_order_filter import ar1_filter


def simulate(spec: NoiseSpec, theta, sigma2: float, w, n_sims: int, *, seed: int) -> np.ndarray:
    """Draw (n, n_sims) noise series from the model (state started from its initial law).

    The state is diagonal, so every component is an independent AR(1) (or random walk)
    x_{t+1} = phi x_t + u_t, drawn over all series at once, plus white noise of variance
    s2 w_t.
    """
    phi, q, p0 = system(spec, theta)
    w = np.asarray(w, dtype=float)
    n = w.size
    rng = np.random.default_rng(seed)
    out = np.sqrt(w)[:, None] * rng.standard_normal((n, n_sims))
    for j in range(phi.size):
        u = np.sqrt(q[j]) * rng.standard_normal((n, n_sims))
        u[0] = np.sqrt(p0[j]) * rng.standard_normal(n_sims)  # x_0 from the initial law
        # x_t = phi x_{t-1} + u_{t-1} for t >= 1, x_0 = u[0]: filter the shifted innovations
        x = ar1_filter(phi[j], u)
        out += x
    return np.sqrt(sigma2) * out


def column_logliks(spec: NoiseSpec, thetas, y_cols, X, mask, w) -> np.ndarray:
    """(G, C) profile log-likelihoods of C response columns under G hyperparameter vectors;
    every column is its own regression on X (beta and s2 profiled per column):
    log L = -1/2 [n log(2 pi RSS / n) + sum m log F + n]."""
    mask = np.asarray(mask, float)
    p = X.shape[1]
    Y = np.where(mask[:, None] > 0, np.column_stack([X, y_cols]), 0.0)
    nobs = float(mask.sum())
    out = []
    for th in np.atleast_2d(thetas):
        V, F = innovations(spec, th, Y, mask, w, grad=False)[:2]
        g = mask / F
        VX, VY = V[:, :p], V[:, p:]
        GX = VX * g[:, None]
        try:
            L = np.linalg.cholesky(GX.T @ VX)
        except np.linalg.LinAlgError:
            out.append(np.full(VY.shape[1], np.nan))
            continue
        R = VY - VX @ cho_solve((L, True), GX.T @ VY)  # RSS from the residuals ("Precision")
        rss = np.sum(g[:, None] * R * R, axis=0)
        out.append(-0.5 * (nobs * np.log(2 * np.pi * rss / nobs)
                           + float(np.sum(mask * np.log(F))) + nobs))
    return np.array(out)
