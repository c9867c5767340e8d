"""One-step prediction, residuals and Kalman denoising with a fitted ARMA model.

Innovations v_t = x_t - x^_{t|t-1} (variance sigma2 F_t), residual a_t = v_t / sqrt(F_t). Denoising
(Hillmer & Tiao 1982): x = s + e, h = min_w S(w), signal ARMA(p, max(p, q)) from
sigma2_s theta_s(z) theta_s(1/z) = sigma2 theta(z) theta(1/z) - h phi(z) phi(1/z); Kalman filter
and RTS smoother.
"""

from __future__ import annotations

from typing import NamedTuple

import jax.numpy as jnp
import numpy as np

from ..errors import ArgumentError
from ..models.buckets import held
from ..models.statespace import arma_state_space, kalman_filter, rts_smoother
from ..support.programs import program


class OneStep(NamedTuple):
    """prediction x^_{t|t-1} (n,), innovation v_t, its variance sigma2 F~_t, and the
    standardised residual a_t = v_t / sqrt(F~_t) (variance sigma2)."""

    prediction: np.ndarray
    innovation: np.ndarray
    innovation_var: np.ndarray
    residual: np.ndarray


class Denoised(NamedTuple):
    """filtered E[s_t | x_1..x_t], smoothed E[s_t | x_1..x_n], the removed noise x - smoothed
    (and x - filtered), the white-noise variance h used, and the signal model."""

    filtered: np.ndarray
    smoothed: np.ndarray
    noise: np.ndarray
    noise_filtered: np.ndarray
    noise_var: float
    signal_phi: np.ndarray
    signal_theta: np.ndarray
    signal_sigma2: float


# The state space is built inside the compiled programs: built eagerly, each of its
# operations was a program of its own, traced, lowered and compiled in every new process
# (~40 of them, seconds of a `fogbayes arma` call).
# The series is held in ``bucket_length(n)`` samples (the tail missing), so that nearby
# lengths share one program; outputs cover the whole array.

@program
def _innovations(phi, theta, sigma2, xb, n):
    f = kalman_filter(arma_state_space(phi, theta, sigma2), xb, 0.0, n_valid=n)
    return f.innov, f.innov_var


@program
def _filtered_and_smoothed(phi, theta, sigma2, xb, n, obs_var):
    ss = arma_state_space(phi, theta, sigma2)
    filt = kalman_filter(ss, xb, obs_var, n_valid=n)
    return filt.filt_mean[:, 0], rts_smoother(ss, filt).mean[:, 0]


def one_step_prediction(phi, theta, sigma2, x) -> OneStep:
    """Exact one-step-ahead prediction and innovations of x under ARMA(phi, theta, sigma2)."""
    x = np.asarray(x, dtype=float)
    xb, n = held(x)
    innov, innov_var = _innovations(jnp.asarray(phi, dtype=float),
                                    jnp.asarray(theta, dtype=float), float(sigma2), xb, n)
    v, F = np.asarray(innov)[:n], np.asarray(innov_var)[:n]
    return OneStep(x - v, v, F, v / np.sqrt(F / float(sigma2)))


def arma_spectrum(phi, theta, sigma2, omega) -> np.ndarray:
    """S(w) = sigma2 |1 - sum theta_j e^{-ijw}|^2 / |1 - sum phi_i e^{-iiw}|^2 (white: S = var)."""
    omega = np.asarray(omega, dtype=float)

    def poly(c):
        c = np.asarray(c, dtype=float)
        k = np.arange(1, c.size + 1)
        return 1.0 - (np.exp(-1j * np.outer(omega, k)) @ c if c.size else 0.0)

    return float(sigma2) * np.abs(poly(theta)) ** 2 / np.abs(poly(phi)) ** 2


def canonical_noise_var(phi, theta, sigma2, *, grid: int = 1 << 14) -> float:
    """h = min_w S(w): the largest white noise the ARMA spectrum contains (grid + refinement)."""
    w = np.linspace(0.0, np.pi, grid + 1)
    s = arma_spectrum(phi, theta, sigma2, w)
    i = int(np.argmin(s))
    lo, hi = w[max(i - 1, 0)], w[min(i + 1, grid)]
    fine = np.linspace(lo, hi, 2001)
    return float(min(s.min(), arma_spectrum(phi, theta, sigma2, fine).min()))


def _autocorr_poly(c: np.ndarray) -> np.ndarray:
    """Coefficients k = 0..m of c(z) c(1/z) for c = [c_0..c_m] (symmetric in k)."""
    m = c.size - 1
    return np.array([np.dot(c[: m + 1 - k], c[k:]) for k in range(m + 1)])


def signal_model(phi, theta, sigma2, noise_var: float) -> tuple[np.ndarray, np.ndarray, float]:
    """(phi, theta_s, sigma2_s) of the signal s = x - e (paper sign), by spectral factorisation."""
    phi, theta = np.atleast_1d(np.asarray(phi, float)), np.atleast_1d(np.asarray(theta, float))
    m = max(phi.size, theta.size)
    th = np.zeros(m + 1)
    th[0], th[1 : theta.size + 1] = 1.0, -theta
    ph = np.zeros(m + 1)
    ph[0], ph[1 : phi.size + 1] = 1.0, -phi
    g = float(sigma2) * _autocorr_poly(th) - float(noise_var) * _autocorr_poly(ph)
    if g[0] <= 1e-12 * float(sigma2):  # nothing left but noise
        return phi, np.zeros(m), 0.0
    coeffs = np.concatenate([g[::-1], g[1:]])  # z^m N(z), degree 2m
    # trailing zero coefficients mean roots at infinity: only finite roots are returned
    roots = np.roots(np.trim_zeros(coeffs, "f"))
    roots = roots[np.argsort(-np.abs(roots))][:m] if roots.size else roots
    b = np.real(np.poly(1.0 / roots)) if roots.size else np.ones(1)  # b(z) = prod(1 - z/r)
    b = np.concatenate([b, np.zeros(m + 1 - b.size)])
    s2 = g[0] / np.dot(b, b)
    return phi, -b[1:], float(s2)


def denoise(phi, theta, sigma2, x, *, noise_var: float | None = None) -> Denoised:
    """Kalman filter and RTS smoother of the signal in x = s + white noise (see module doc).

    ``noise_var`` None uses the canonical h = min S(w); a larger h than that would need
    a negative signal spectrum and raises a FogbayesError.
    """
    h_max = canonical_noise_var(phi, theta, sigma2)
    h = h_max if noise_var is None else float(noise_var)
    if not 0.0 <= h <= h_max * (1 + 1e-9):
        raise ArgumentError(f"noise_var={h:g} is outside [0, {h_max:g}], the white noise "
                            "this ARMA spectrum can contain", fix="leave noise_var unset "
                            "(canonical decomposition) or pass a smaller value")
    h = min(h, h_max)
    sphi, sth, s2 = signal_model(phi, theta, sigma2, h)
    xn = np.asarray(x, dtype=float)
    n = xn.shape[0]
    if s2 == 0.0:
        z = np.zeros(n)
        return Denoised(z, z, xn, xn, h, sphi, sth, 0.0)
    # the smoother runs back over the missing tail unchanged (no gain there), so from
    # t = n - 1 down it is the smoother of x_1..x_n
    xb, _ = held(xn)
    fs, ms = _filtered_and_smoothed(jnp.asarray(sphi, dtype=float), jnp.asarray(sth, dtype=float),
                                    float(s2), xb, n, float(h))
    fs, ms = np.asarray(fs)[:n], np.asarray(ms)[:n]
    return Denoised(fs, ms, xn - ms, xn - fs, h, sphi, sth, s2)
