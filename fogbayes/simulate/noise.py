"""Stochastic gyro noise with exactly specified parameters (rate in deg/h).

sigma^2(tau) = 3 Q^2/tau^2 + N_s^2/tau + (2 ln2/pi) B^2 + K_s^2 tau/3 + R_s^2 tau^2/2 (units of
:mod:`fogbayes.allan.model`). Q: differentiated white angle noise; N: white rate, std
N_s sqrt(fs); B: FFT-shaped 1/f noise, PSD B^2 / (pi f), from a record ``span`` times longer
(:func:`flicker_avar` gives its exact AVAR); K: interval means of a Brownian motion, drawn
exactly; R: the ramp R_s t. Each term has its own stream from (seed, term).
"""

from __future__ import annotations

import math

import numpy as np
from scipy import linalg, signal

from ._checks import SimulationParameterError, positive, positive_int, seed_int

_TAGS = {"Q": 1, "N": 2, "B": 3, "K": 4, "markov": 5, "arma": 6}


def _rng(seed: int, tag: str) -> np.random.Generator:
    return np.random.default_rng([seed_int(seed), _TAGS[tag]])


def white_noise(n: int, fs: float, *, seed: int, N: float) -> np.ndarray:
    """Angle random walk: white rate noise, sigma^2(tau) = (60 N)^2 / tau (deg/h, N deg/sqrt h)."""
    n, fs, N = positive_int(n, "n"), positive(fs, "fs"), positive(N, "N", allow_zero=True)
    return 60.0 * N * math.sqrt(fs) * _rng(seed, "N").standard_normal(n)


def quantization_noise(n: int, fs: float, *, seed: int, Q: float) -> np.ndarray:
    """Angle quantization: x_k = (e_{k+1} - e_k) fs, e ~ N(0, Q^2); sigma^2 = 3 Q^2 / tau^2."""
    n, fs, Q = positive_int(n, "n"), positive(fs, "fs"), positive(Q, "Q", allow_zero=True)
    e = Q * _rng(seed, "Q").standard_normal(n + 1)
    return np.diff(e) * fs


def flicker_noise(n: int, fs: float, *, seed: int, B: float, span: int = 4) -> np.ndarray:
    """Bias instability as 1/f noise: one-sided PSD S(f) = B^2 / (pi f), f = k fs / L,
    the first ``n`` samples of a periodic sequence of length L = span n (module doc).

    For a flat one-sided PSD h/f the Allan variance is 2 ln2 h = (2 ln2 / pi) B^2, i.e.
    ADEV 0.664 B. numpy's irfft gives bin k the variance 2 E|X_k|^2 / n^2, so
    E|X_k|^2 = S(f_k) fs n / 2 puts S(f_k) fs / n (the PSD times the bin width) in bin k.
    """
    n, fs, B = positive_int(n, "n"), positive(fs, "fs"), positive(B, "B", allow_zero=True)
    span = positive_int(span, "span")
    if B == 0.0 or n < 2:
        return np.zeros(n)
    rng = _rng(seed, "B")
    L = span * n
    k = np.arange(1, L // 2 + 1)
    psd = B * B / (math.pi * (k * fs / L))
    amp = np.sqrt(psd * fs * L / 4.0)  # std of real and of imaginary part
    spec = np.zeros(L // 2 + 1, dtype=complex)
    spec[1:] = amp * (rng.standard_normal(k.size) + 1j * rng.standard_normal(k.size))
    if L % 2 == 0:  # the Nyquist bin is real and covers half a bin width: S fs / (2 L)
        spec[-1] = math.sqrt(2.0) * amp[-1] * rng.standard_normal()
    return np.fft.irfft(spec, L)[:n]


def flicker_avar(m, n: int, fs: float, *, B: float, span: int = 4) -> np.ndarray:
    """Exact expected Allan variance of :func:`flicker_noise` at cluster sizes ``m``.

    The generator is a stationary Gaussian sequence, a sum of independent random-phase
    cosines at f_k = k fs / L (L = span n) with variances v_k = S(f_k) fs / L (half that at
    Nyquist); keeping the first n samples leaves its expectation unchanged.
    For one cosine the m-sample mean has amplitude ratio sin(m w/2) / (m sin(w/2)) and the
    difference of adjacent means a further 2 sin(m w/2), w = 2 pi f / fs, so

        AVAR(m) = sum_k 2 v_k sin^4(pi f_k m / fs) / (m^2 sin^2(pi f_k / fs)).
    """
    m = np.atleast_1d(np.asarray(m, dtype=float))
    n = span * n
    k = np.arange(1, n // 2 + 1)
    f = k * fs / n
    var_k = B * B / (math.pi * f) * fs / n
    if n % 2 == 0:
        var_k[-1] /= 2.0  # the Nyquist bin covers half a bin width
    x = np.pi * f / fs
    h2 = np.sin(np.outer(m, x)) ** 4 / (m[:, None] ** 2 * np.sin(x) ** 2)
    return (2.0 * var_k[None, :] * h2).sum(axis=1)


def random_walk_noise(n: int, fs: float, *, seed: int, K: float) -> np.ndarray:
    """Rate random walk, sample-averaged: sigma^2(tau) = K_s^2 tau / 3, K_s = K / 60.

    Over one sample interval h = 1/fs a Brownian motion W of intensity K_s has increment
    D ~ N(0, K_s^2 h) and interval mean W_start + I with Var I = K_s^2 h / 3,
    Cov(I, D) = K_s^2 h / 2; so I = D / 2 + K_s sqrt(h / 12) z, independent z.
    """
    n, fs, K = positive_int(n, "n"), positive(fs, "fs"), positive(K, "K", allow_zero=True)
    ks, h = K / 60.0, 1.0 / fs
    z = _rng(seed, "K").standard_normal((2, n))
    d = ks * math.sqrt(h) * z[0]
    start = np.concatenate(([0.0], np.cumsum(d)[:-1]))
    return start + 0.5 * d + ks * math.sqrt(h / 12.0) * z[1]


def rate_ramp(n: int, fs: float, *, R: float) -> np.ndarray:
    """Rate ramp R_s t (t = k / fs from 0, R_s = R / 3600): sigma^2(tau) = R_s^2 tau^2 / 2."""
    n, fs = positive_int(n, "n"), positive(fs, "fs")
    return float(R) / 3600.0 * np.arange(n) / fs


def allan_noise(n: int, fs: float, *, seed: int, Q: float = 0.0, N: float = 0.0,
                B: float = 0.0, K: float = 0.0, R: float = 0.0,
                flicker_span: int = 4) -> np.ndarray:
    """Rate noise (deg/h) whose Allan variance is the five-term model of the module docstring.

    Args:
        n: number of samples; fs: sample rate (Hz); seed: explicit integer seed.
        Q arcsec, N deg/sqrt(h), B deg/h, K deg/h^1.5, R deg/h^2 (all >= 0 except R).
        flicker_span: the flicker is drawn over this many times n (:func:`flicker_noise`);
            1 for a caller that draws a longer record and cuts it itself.

    Example:
        >>> x = allan_noise(1000, 10.0, seed=0, N=0.01)
        >>> x.shape
        (1000,)
    """
    n, fs = positive_int(n, "n"), positive(fs, "fs")
    out = np.zeros(n)
    if Q:
        out += quantization_noise(n, fs, seed=seed, Q=Q)
    if N:
        out += white_noise(n, fs, seed=seed, N=N)
    if B:
        out += flicker_noise(n, fs, seed=seed, B=B, span=flicker_span)
    if K:
        out += random_walk_noise(n, fs, seed=seed, K=K)
    if R:
        out += rate_ramp(n, fs, R=R)
    return out


def allan_variance_model(tau, *, Q=0.0, N=0.0, B=0.0, K=0.0, R=0.0) -> np.ndarray:
    """The five-term sigma^2(tau) in (deg/h)^2 for tau in s (canonical parameter units)."""
    tau = np.asarray(tau, dtype=float)
    ns, ks, rs = 60.0 * N, K / 60.0, R / 3600.0
    return (3 * Q**2 / tau**2 + ns**2 / tau + 2 * math.log(2) / math.pi * B**2
            + ks**2 * tau / 3 + rs**2 * tau**2 / 2)


def markov_noise(n: int, fs: float, *, seed: int, sigma: float, tau_c: float) -> np.ndarray:
    """First-order Gauss-Markov noise, stationary std ``sigma`` (deg/h), correlation time tau_c (s).

    Exact discretisation x_k = a x_{k-1} + sqrt(1 - a^2) sigma w_k, a = exp(-1 / (fs tau_c)),
    x_0 ~ N(0, sigma^2), so Var x_k = sigma^2 and Corr(x_k, x_{k+j}) = a^j = exp(-j dt / tau_c).
    """
    n, fs = positive_int(n, "n"), positive(fs, "fs")
    sigma, tau_c = positive(sigma, "sigma", allow_zero=True), positive(tau_c, "tau_c")
    a = math.exp(-1.0 / (fs * tau_c))
    w = _rng(seed, "markov").standard_normal(n)
    w[1:] *= math.sqrt(-math.expm1(-2.0 / (fs * tau_c)))  # sqrt(1 - a^2) without cancellation
    return sigma * signal.lfilter([1.0], [1.0, -a], w)


def arma_noise(n: int, *, seed: int, phi=(), theta=(), sigma: float = 1.0) -> np.ndarray:
    """Stationary ARMA(p, q), paper 002 sign: x_t = sum phi_i x_{t-i} + a_t - sum theta_j a_{t-j}.

    a_t ~ N(0, sigma^2) (``sigma`` is the innovation std). Filtered by lfilter with
    b = [1, -theta], a = [1, -phi]; its initial state is drawn from the exact stationary
    distribution (discrete Lyapunov equation of the filter's state), so no burn-in is needed.
    Raises SimulationParameterError if the AR part is not stationary.
    """
    n = positive_int(n, "n")
    sigma = positive(sigma, "sigma", allow_zero=True)
    phi = np.atleast_1d(np.asarray(phi, dtype=float))
    theta = np.atleast_1d(np.asarray(theta, dtype=float))
    a = np.concatenate(([1.0], -phi))
    b = np.concatenate(([1.0], -theta))
    if phi.size and np.max(np.abs(np.roots(a))) >= 1.0:
        raise SimulationParameterError(
            f"the AR part phi={phi.tolist()} is not stationary (a root of the AR polynomial "
            "lies on or outside the unit circle)", argument="phi",
            fix="choose phi with all roots of z^p - phi_1 z^(p-1) - ... - phi_p inside |z| < 1")
    rng = _rng(seed, "arma")
    e = sigma * rng.standard_normal(n)
    size = max(a.size, b.size)
    if size == 1:
        return e
    a = np.pad(a, (0, size - a.size))
    b = np.pad(b, (0, size - b.size))
    # Transposed direct form II: z_new = F z + g e, y = z_0 + b_0 e (see scipy.signal.lfilter).
    F = np.zeros((size - 1, size - 1))
    F[:, 0] = -a[1:]
    F[np.arange(size - 2), np.arange(1, size - 1)] = 1.0
    g = b[1:] - a[1:] * b[0]
    P = linalg.solve_discrete_lyapunov(F, sigma**2 * np.outer(g, g))
    zi = rng.multivariate_normal(np.zeros(size - 1), (P + P.T) / 2.0, method="eigh")
    y, _ = signal.lfilter(b, a, e, zi=zi)
    return y


def sinusoid(n: int, fs: float, *, amplitude: float, frequency: float,
             phase: float = 0.0) -> np.ndarray:
    """Sinusoidal rate A sin(2 pi f t + phase), t = k / fs (deg/h).

    Its Allan variance is A^2 sin^4(pi f tau) / (pi f tau)^2 (paper 002, table 1, with the
    amplitude convention sigma^2 = Omega0^2 (sin^2(pi f tau) / (pi f tau))^2).
    """
    n, fs = positive_int(n, "n"), positive(fs, "fs")
    t = np.arange(n) / fs
    return float(amplitude) * np.sin(2.0 * math.pi * float(frequency) * t + float(phase))
