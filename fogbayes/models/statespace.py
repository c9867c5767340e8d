"""The package's Kalman filter (pure JAX), and the ARMA(p, q) state space and RTS smoother on it.

:func:`linear_gaussian_filter` runs y_t = z'alpha_t + e_t, e_t ~ N(0, h_t), alpha_{t+1} = T alpha_t
+ u_t, u_t ~ N(0, Q), on one or several columns that share the gains. The ARMA models
(:func:`kalman_filter`) and the loop's noise model (:mod:`fogbayes.inference.noise_ssm`) are its
two systems; the CPU fits run the noise model's Numba backend, held to it by the tests.

ARMA in Harvey's form, r = max(p, q + 1): alpha_{t+1} = T alpha_t + R a_{t+1}, T = [phi | I; 0],
R = [1, -theta_1, ..., -theta_{r-1}], y_t = alpha_t[0] + e_t, e_t ~ N(0, h) (h = 0: exact ARMA).
Start N(0, P0), P0 = T P0 T' + sigma2 RR' solved via (I - T (x) T) vec P0 = vec Q.
"""

from __future__ import annotations

from functools import partial
from typing import NamedTuple

import jax
import jax.numpy as jnp
from jax import lax

from ..support.programs import program

Array = jax.Array


class ArmaStateSpace(NamedTuple):
    """Transition ``T`` (r, r), selection ``R`` (r,) and innovation variance ``sigma2``."""

    T: Array
    R: Array
    sigma2: Array


class FilterResult(NamedTuple):
    """Kalman filter output for n observations and r states.

    pred_mean (n, r), pred_cov (n, r, r): alpha_t | y_1..y_{t-1};
    filt_mean (n, r), filt_cov (n, r, r): alpha_t | y_1..y_t;
    innov (n,) v_t = y_t - E[y_t | past], innov_var (n,) F_t; loglik: sum of log N(v_t; 0, F_t).
    """

    pred_mean: Array
    pred_cov: Array
    filt_mean: Array
    filt_cov: Array
    innov: Array
    innov_var: Array
    loglik: Array


class SmootherResult(NamedTuple):
    """RTS smoother output: alpha_t | y_1..y_n, mean (n, r) and covariance (n, r, r)."""

    mean: Array
    cov: Array


def state_dim(p: int, q: int) -> int:
    """r = max(p, q + 1), the number of states of Harvey's form."""
    return max(p, q + 1)


def arma_state_space(phi: Array, theta: Array, sigma2=1.0) -> ArmaStateSpace:
    """Build (T, R, sigma2) for ARMA(p, q) in the paper's sign convention (see module doc)."""
    phi = jnp.atleast_1d(jnp.asarray(phi, dtype=float))
    theta = jnp.atleast_1d(jnp.asarray(theta, dtype=float))
    p, q = phi.shape[-1], theta.shape[-1]
    r = state_dim(p, q)
    phi_full = jnp.zeros(r).at[:p].set(phi)
    R = jnp.zeros(r).at[0].set(1.0).at[1 : q + 1].set(-theta)
    T = jnp.zeros((r, r)).at[:, 0].set(phi_full).at[jnp.arange(r - 1), jnp.arange(1, r)].set(1.0)
    return ArmaStateSpace(T, R, jnp.asarray(sigma2, dtype=float))


def apply_T(phi_full: Array, M: Array) -> Array:
    """T @ M for the companion-like T above, without a dense matmul (cheap inside scans).

    Row i of T M is phi_i M[0] + M[i + 1] (M[r] = 0).
    """
    shifted = jnp.concatenate([M[1:], jnp.zeros_like(M[:1])], axis=0)
    lead = phi_full.reshape((-1,) + (1,) * (M.ndim - 1))
    return lead * M[0] + shifted


def stationary_cov(T: Array, Q: Array) -> Array:
    """Solve the discrete Lyapunov equation P = T P T' + Q exactly (vec/Kronecker form).

    r is small (<= 4 for the paper's models), so the r^2 x r^2 solve is cheap and, unlike
    a doubling iteration, exact and smoothly differentiable. Non-stationary T gives a
    singular or indefinite system: callers keep |PACF| < 1 (see :mod:`fogbayes.models.arma`).
    """
    r = T.shape[0]
    A = jnp.eye(r * r) - jnp.kron(T, T)
    P = jnp.linalg.solve(A, Q.reshape(-1)).reshape(r, r)
    return 0.5 * (P + P.T)


def linear_gaussian_filter(transition, Q: Array, z: Array, P0: Array, Y: Array, h: Array,
                           mask: Array | None = None, *, states: bool = True, unroll: int = 8):
    """Kalman filter of every column of Y with shared gains, started at N(0, P0).

    ``transition(M)`` = T M for M (r, ...); Q (r, r), z (r,), P0 (r, r); Y (n,) or (n, C);
    h (n,) observation variances (inf: a missing sample, no update, F_t = inf); ``mask`` (n,)
    optional 0/1 weights of the update (0: a missing sample whose F_t stays finite).
    Per step: v_t = y_t - z'a_t, F_t = z'P_t z + h_t, k_t = P_t z / F_t,
    a_t|t = a_t + m_t k_t v_t, P_t|t = P_t - m_t k_t (P_t z)',
    a_{t+1} = T a_t|t, P_{t+1} = T P_t|t T' + Q (both covariances symmetrised).
    Returns (a_t, P_t, a_t|t, P_t|t, v_t, F_t) stacked over t, or (v, F) with ``states=False``.
    """
    Y = jnp.asarray(Y, dtype=float)
    m = jnp.ones(Y.shape[0]) if mask is None else jnp.asarray(mask, dtype=float)

    def step(carry, inp):
        a, P = carry
        yt, ht, mt = inp
        Pz = P @ z
        F = z @ Pz + ht
        v = yt - z @ a
        k = Pz / F
        af = a + mt * (k[:, None] * v if Y.ndim > 1 else k * v)
        Pf = P - mt * jnp.outer(k, Pz)
        Pf = 0.5 * (Pf + Pf.T)
        Pn = transition(transition(Pf).T) + Q
        out = (a, P, af, Pf, v, F) if states else (v, F)
        return (transition(af), 0.5 * (Pn + Pn.T)), out

    a0 = jnp.zeros(z.shape + Y.shape[1:])
    return lax.scan(step, (a0, P0), (Y, jnp.asarray(h, dtype=float), m), unroll=unroll)[1]


@partial(program, static_argnames=("unroll",))
def kalman_filter(ss: ArmaStateSpace, y: Array, obs_var=0.0, *, n_valid=None,
                  unroll: int = 8) -> FilterResult:
    """:func:`linear_gaussian_filter` of the ARMA system, y_t = alpha_t[0] + e_t,
    e_t ~ N(0, obs_var), started stationary, and the log-likelihood sum log N(v_t; 0, F_t).

    ``n_valid`` (traced): only y_1..y_n are observed; later samples are missing, which is
    h = inf there (F_t = inf, K_t = 0: no update; their F_t is returned as inf and they add
    no log-likelihood). So the filter at t < n, the log-likelihood and an RTS smoother run
    over the whole array equal those of y_1..y_n alone, and one program serves every
    length up to len(y) (:mod:`fogbayes.models.buckets`).
    """
    T, R, sigma2 = ss
    phi_full = T[:, 0]
    Q = sigma2 * jnp.outer(R, R)
    y = jnp.asarray(y, dtype=float)
    h = jnp.broadcast_to(jnp.asarray(obs_var, dtype=float), y.shape)
    if n_valid is not None:  # a missing sample: infinite observation variance
        h = jnp.where(jnp.arange(y.shape[0]) < n_valid, h, jnp.inf)
    z = jnp.zeros(T.shape[0]).at[0].set(1.0)
    a, P, af, Pf, v, F = linear_gaussian_filter(
        lambda M: apply_T(phi_full, M), Q, z, stationary_cov(T, Q), y, h, unroll=unroll)
    ll = -0.5 * (jnp.log(2 * jnp.pi * F) + v * v / F)
    if n_valid is not None:
        ll = jnp.where(jnp.arange(y.shape[0]) < n_valid, ll, 0.0)
    return FilterResult(a, P, af, Pf, v, F, jnp.sum(ll))


@partial(program, static_argnames=("unroll",))
def rts_smoother(ss: ArmaStateSpace, filt: FilterResult, *, unroll: int = 8) -> SmootherResult:
    """Rauch-Tung-Striebel smoother, backwards from alpha_n | y_1..y_n.

    J_t = P_t|t T' P_{t+1}^{-1}, m_t = a_t|t + J_t (m_{t+1} - a_{t+1}),
    S_t = P_t|t + J_t (S_{t+1} - P_{t+1}) J_t'.
    P_{t+1} can be singular (a pure AR state is exactly known after p steps), so the
    gain uses a pseudo-inverse solve; the smoothed moments are unique regardless.
    """
    phi_full = ss.T[:, 0]

    def step(carry, inp):
        m_next, S_next = carry
        af, Pf, a_next, P_next = inp
        C = apply_T(phi_full, Pf).T  # P_t|t T'
        J = C @ jnp.linalg.pinv(P_next, hermitian=True, rtol=1e-12)
        m = af + J @ (m_next - a_next)
        S = Pf + J @ (S_next - P_next) @ J.T
        S = 0.5 * (S + S.T)
        return (m, S), (m, S)

    last = (filt.filt_mean[-1], filt.filt_cov[-1])
    inputs = (filt.filt_mean[:-1], filt.filt_cov[:-1], filt.pred_mean[1:], filt.pred_cov[1:])
    _, (m, S) = lax.scan(step, last, inputs, reverse=True, unroll=unroll)
    mean = jnp.concatenate([m, last[0][None]], axis=0)
    cov = jnp.concatenate([S, last[1][None]], axis=0)
    return SmootherResult(mean, cov)
