"""ARMA(p, q) noise model: exact Gaussian likelihood and a stationary/invertible parameterisation.

Paper 002 eq. 8: x_t = sum phi_i x_{t-i} + a_t - sum theta_j a_{t-j}, a_t ~ N(0, sigma2)
(statsmodels' MA = -theta). log L = -1/2 sum_t [log(2 pi F_t) + v_t^2 / F_t] by the Kalman filter
of :mod:`fogbayes.models.statespace` with sigma2 = 1, so sigma2_hat = (1/n) sum v_t^2 / F~_t; pure
AR(p) in closed form. :func:`pacf_to_ar` (Durbin-Levinson on r in (-1, 1), r = tanh u; Jones 1980)
gives stationary AR and invertible MA polynomials. Used by :mod:`fogbayes.arma`, the composite
family and :mod:`fogbayes.inference.bayes`.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
from jax import lax

from ..models.statespace import apply_T, arma_state_space, kalman_filter, stationary_cov

Array = jax.Array

#: The sign convention, stated in every exported document.
SIGN_CONVENTION = "x_t = sum_i phi_i x_{t-i} + a_t - sum_j theta_j a_{t-j}, a_t ~ N(0, sigma2)"


class ArmaParams(NamedTuple):
    """ARMA(p, q) parameters in the paper's sign convention: phi (p,), theta (q,), sigma2."""

    phi: Array
    theta: Array
    sigma2: Array


# --------------------------------------------------------------------------- reparameterisation
def pacf_to_ar(pacf: Array) -> Array:
    """Partial autocorrelations r_1..r_p (|r_k| < 1) -> AR coefficients phi_1..phi_p.

    Durbin-Levinson: phi^(k)_k = r_k, phi^(k)_j = phi^(k-1)_j - r_k phi^(k-1)_{k-j}.
    |r_k| < 1 for all k  <=>  1 - sum phi_i z^i has all roots outside the unit circle.
    Works on the last axis (leading axes are a batch); p is static.

    >>> pacf_to_ar(jnp.array([0.5, -0.2]))   # doctest: +SKIP
    Array([ 0.6, -0.2], dtype=float64)
    """
    pacf = jnp.asarray(pacf, dtype=float)
    p = pacf.shape[-1]
    phi = pacf[..., :0]
    for k in range(p):
        rk = pacf[..., k : k + 1]
        phi = jnp.concatenate([phi - rk * phi[..., ::-1], rk], axis=-1)
    return phi


def ar_to_pacf(phi: Array) -> Array:
    """Inverse of :func:`pacf_to_ar` (reverse Durbin-Levinson); |result| < 1 iff stationary.

    phi^(k-1)_j = (phi^(k)_j + r_k phi^(k)_{k-j}) / (1 - r_k^2), r_k = phi^(k)_k.
    """
    phi = jnp.asarray(phi, dtype=float)
    p = phi.shape[-1]
    out = []
    for k in range(p, 0, -1):
        rk = phi[..., k - 1 : k]
        out.append(rk)
        head = phi[..., : k - 1]
        phi = (head + rk * head[..., ::-1]) / (1.0 - rk * rk)
    return jnp.concatenate(out[::-1], axis=-1) if out else phi[..., :0]


def unconstrained_to_params(u_phi: Array, u_theta: Array) -> tuple[Array, Array]:
    """R^p x R^q -> (stationary phi, invertible theta) via r = tanh(u) and Durbin-Levinson."""
    return pacf_to_ar(jnp.tanh(u_phi)), pacf_to_ar(jnp.tanh(u_theta))


def params_to_unconstrained(phi: Array, theta: Array, clip: float = 0.999) -> tuple[Array, Array]:
    """Inverse of :func:`unconstrained_to_params`; PACFs are clipped into (-clip, clip)."""
    rp = jnp.clip(ar_to_pacf(phi), -clip, clip)
    rq = jnp.clip(ar_to_pacf(theta), -clip, clip)
    return jnp.arctanh(rp), jnp.arctanh(rq)


# --------------------------------------------------------------------------- moments
def arma_acov(phi: Array, theta: Array, sigma2, nlags: int) -> Array:
    """Autocovariances gamma_0..gamma_{nlags-1}: gamma_k = e1' T^k P0 e1 (state-space form)."""
    T, R, s2 = arma_state_space(phi, theta, sigma2)
    M = stationary_cov(T, s2 * jnp.outer(R, R))
    out = []
    for _ in range(nlags):
        out.append(M[0, 0])
        M = apply_T(T[:, 0], M)
    return jnp.stack(out) if out else jnp.zeros(0)


# --------------------------------------------------------------------------- likelihood
def allpole_filter(theta: Array, u: Array, *, unroll: int = 1) -> Array:
    """y_t = u_t + sum_j theta_j y_{t-j} along axis 0 (y_{<=0} = 0); u (n, ...) -> y (n, ...).

    This is the inverse of the paper's MA polynomial, theta(L)^{-1}. A scan whose carry is
    the last q outputs: cheap forwards and, unlike a covariance recursion, cheap in reverse.
    """
    q = theta.shape[-1]
    if q == 0:
        return u

    def step(buf, ut):
        yt = ut + jnp.tensordot(theta, buf, axes=1)
        return jnp.concatenate([yt[None], buf[:-1]], axis=0), yt

    _, y = lax.scan(step, jnp.zeros((q,) + u.shape[1:]), u, unroll=unroll)
    return y


def _initial_state_drive(T: Array, R: Array, theta: Array) -> Array:
    """D (r, r) with G = theta(L)^{-1} D, G[t] = e1' T A^(t-1), A = (I - R e1') T (t >= 1).

    G[t] is how the residual at time t depends on the pre-sample state alpha_0. For
    t > r the pre-sample values no longer enter directly and G obeys the homogeneous
    recursion G[t] = sum_j theta_j G[t-j], so the drive D is zero past its first r rows,
    which are returned: D[t] = G[t] - sum_{j <= t} theta_j G[t-j].
    """
    r = T.shape[0]
    A = T - jnp.outer(R, T[0])
    rows, M = [], jnp.eye(r)
    for _ in range(r):
        rows.append((T @ M)[0])
        M = A @ M
    q = theta.shape[-1]
    return jnp.stack([rows[t] - sum(theta[j] * rows[t - 1 - j] for j in range(min(q, t)))
                      for t in range(r)])


def profile_terms(phi: Array, theta: Array, x: Array, *, n_valid=None, unroll: int = 1
                  ) -> tuple[Array, Array]:
    """(log det Sigma~, x' Sigma~^-1 x) for Sigma = sigma2 Sigma~, the exact ARMA covariance.

    Exact "conditional residuals + initial-state correction" form (equal to the Kalman
    filter's sum log F~_t and sum v_t^2 / F~_t): with the Harvey state alpha_0 ~ N(0,
    sigma2 Omega) (Omega from the Lyapunov equation) the residuals are a = c - G alpha_0,
    where c are the residuals computed with all pre-sample values zero,
    c = theta(L)^{-1} phi(L) x, and G (n, r) their response to alpha_0. Integrating alpha_0
    out of N(a; 0, sigma2 I) N(alpha_0; 0, sigma2 Omega) (the map a -> x has unit Jacobian):

        log det Sigma~   = log det(I + Omega G'G)
        x' Sigma~^-1 x   = c'c - b' (I + Omega G'G)^-1 Omega b,   b = G'c.

    G = theta(L)^{-1} D with D non-zero only in its first r rows, so with h the impulse
    response of theta(L)^{-1}: G'c = D' [sum_t h_{t-s} c_t]_s and G'G = D' H D,
    H_{ss'} = sum_t h_{t-s} h_{t-s'} (s, s' < r) -- shifted dot products. The only
    sequential work is one two-column all-pole filter of length n (c and h); value and
    gradient cost O(n q). Pure AR needs no scan at all.

    ``n_valid`` (a traced integer, default all of x) takes only x_1..x_n of a longer array
    x (n <= len(x); what follows is ignored): every filter is causal, so c and h at t < n do
    not see the tail, and the sums over t < n drop it with a mask. One compiled program
    then serves every length up to len(x) (:func:`fogbayes.models.buckets.bucket_length`).
    """
    phi = jnp.atleast_1d(jnp.asarray(phi, dtype=float))
    theta = jnp.atleast_1d(jnp.asarray(theta, dtype=float))
    x = jnp.asarray(x, dtype=float)
    n, p = x.shape[-1], phi.shape[-1]
    T, R, _ = arma_state_space(phi, theta, 1.0)
    r = T.shape[0]
    Omega = stationary_cov(T, jnp.outer(R, R))
    # w_t = x_t - sum_i phi_i x_{t-i} with pre-sample x = 0, as a sum of shifted copies
    w = x - sum(phi[i] * jnp.concatenate([jnp.zeros(min(i + 1, n)), x[: max(n - i - 1, 0)]])
                for i in range(p))
    impulse = jnp.zeros(n).at[0].set(1.0)
    ch = allpole_filter(theta, jnp.stack([w, impulse], axis=1), unroll=unroll)
    c, h = ch[:, 0], ch[:, 1]
    index = jnp.arange(n)
    if n_valid is not None:  # t >= n_valid: outside the series (see docstring)
        c = jnp.where(index < n_valid, c, 0.0)
    D = _initial_state_drive(T, R, theta)  # (r, r): the non-zero rows of the drive
    k = min(r, n)
    Gc = jnp.stack([jnp.dot(h[: n - s], c[s:]) for s in range(k)])

    def lagged(m: int, lag: int) -> Array:
        """h_j for j < m, as h_{t-lag} at t = j + lag: zero where t is past the series."""
        return h[:m] if n_valid is None else jnp.where(index[:m] + lag < n_valid, h[:m], 0.0)

    # H[s, u] = sum_{t < n} h_{t-s} h_{t-u} = h[u-s : n-s] . h[: n-u] for u >= s
    H = jnp.stack([jnp.stack([jnp.dot(h[abs(u - s) : n - min(s, u)],
                                      lagged(n - max(s, u), max(s, u)))
                              for u in range(k)]) for s in range(k)])
    b = D[:k].T @ Gc
    M = D[:k].T @ H @ D[:k]
    S = jnp.eye(r) + Omega @ M
    logdet = jnp.linalg.slogdet(S)[1]
    quad = c @ c - b @ jnp.linalg.solve(S, Omega @ b)
    return logdet, quad


def arma_loglik(phi: Array, theta: Array, sigma2, x: Array, *, method: str = "fast",
                n_valid=None, unroll: int = 1) -> Array:
    """Exact Gaussian log-likelihood of zero-mean stationary ARMA(p, q) data x (n,).

    log L = -1/2 [ n log(2 pi sigma2) + log det Sigma~ + x' Sigma~^-1 x / sigma2 ]
          = -1/2 sum_t [ log(2 pi sigma2 F~_t) + v_t^2 / (sigma2 F~_t) ]   (Kalman form)

    Paper sign convention (x_t = sum phi_i x_{t-i} + a_t - sum theta_j a_{t-j}); phi (p,)
    and theta (q,) may be empty, their lengths are static. ``method="fast"`` (default)
    uses :func:`profile_terms` (a q-term scan, cheap gradients); ``method="kalman"`` runs
    the Kalman filter of :mod:`fogbayes.models.statespace` (same number to ~1e-12,
    slower gradients). Differentiable in all arguments (x included, so it serves as the
    noise likelihood of residual = data - model), jit- and vmap-able. Non-stationary phi
    gives NaN: keep |PACF| < 1, e.g. through :func:`pacf_to_ar`. ``n_valid``: the series
    is x_1..x_n of a longer array (:func:`profile_terms`).

    Example::

        x = jnp.array([0.3, -0.1, 0.4, 0.2])
        arma_loglik(jnp.array([0.5]), jnp.array([0.2]), 1.0, x)   # ARMA(1, 1)
        arma_loglik(jnp.array([0.5]), jnp.zeros(0), 1.0, x)       # AR(1), no scan
    """
    x = jnp.asarray(x, dtype=float)
    n = x.shape[-1] if n_valid is None else n_valid
    sigma2 = jnp.asarray(sigma2, dtype=float)
    if method == "kalman":
        return kalman_filter(arma_state_space(phi, theta, sigma2), x, n_valid=n_valid,
                             unroll=unroll).loglik
    if method != "fast":
        raise ValueError(f"method must be 'fast' or 'kalman', got {method!r}")
    slf, ssq = profile_terms(phi, theta, x, n_valid=n_valid, unroll=unroll)
    return -0.5 * (n * jnp.log(2 * jnp.pi * sigma2) + slf + ssq / sigma2)


def arma_profile_loglik(phi: Array, theta: Array, x: Array, *, n_valid=None,
                        unroll: int = 1) -> tuple[Array, Array]:
    """Log-likelihood maximised over sigma2, and that sigma2_hat = (1/n) sum v_t^2 / F~_t.

    log L_p = -1/2 [ n log(2 pi sigma2_hat) + sum log F~_t + n ].
    ``n_valid``: the series is x_1..x_n of a longer array (:func:`profile_terms`).
    """
    x = jnp.asarray(x, dtype=float)
    n = x.shape[-1] if n_valid is None else n_valid
    slf, ssq = profile_terms(phi, theta, x, n_valid=n_valid, unroll=unroll)
    s2 = ssq / n
    return -0.5 * (n * jnp.log(2 * jnp.pi * s2) + slf + n), s2
