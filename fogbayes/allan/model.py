"""Allan-variance noise models as pure functions of tau (paper 002 table 1; IEEE 952); NumPy or JAX.

sigma^2(tau) = 3 Q^2/tau^2 + N_s^2/tau + (2 ln2/pi) B^2 + K_s^2 tau/3 + R_s^2 tau^2/2 (deg/h, s);
Q arcsec, N deg/sqrt(h) (N_s = 60 N), B deg/h, K deg/h^1.5 (K_s = K/60), R deg/h^2 (R_s = R/3600).
Paper 002's conversions of s2 = sum C_n^2 tau^n: :func:`params_from_coefficients`,
:func:`coefficients_from_params`. Gauss-Markov (sigma, T_c):
(q_c T_c)^2/tau [1 - T_c/(2 tau)(3 - 4 e^{-tau/T_c} + e^{-2tau/T_c})], q_c^2 = 2 sigma^2/T_c;
sinusoid: Omega_0^2 (sin^2(pi f_0 tau) / (pi f_0 tau))^2.
"""

from __future__ import annotations

import math
from typing import NamedTuple

# the term names, document units and ADEV floor / B live below the families (the datasheet
# prior of fogbayes.inference uses them too); offered here as before
from ..models.allan_terms import BI_FACTOR, TERMS, UNITS  # noqa: F401
from ..support.xp import namespace

#: log-log slope of the deviation sigma(tau) for each term
SLOPES = {"Q": -1.0, "N": -0.5, "B": 0.0, "K": 0.5, "R": 1.0}
#: exponent n of tau in each variance term
POWERS = {"Q": -2, "N": -1, "B": 0, "K": 1, "R": 2}
ARCSEC_IN_URAD = math.pi / (180.0 * 3600.0) * 1e6
#: variance coefficient a_n (sigma^2 = sum a_n tau^n) per squared canonical parameter
_A_PER_P2 = {"Q": 3.0, "N": 3600.0, "B": 2.0 * math.log(2.0) / math.pi,
             "K": 1.0 / (3.0 * 3600.0), "R": 1.0 / (2.0 * 3600.0**2)}


class AllanParams(NamedTuple):
    """Five-term noise parameters in canonical units (see the module docstring)."""

    Q: float = 0.0
    N: float = 0.0
    B: float = 0.0
    K: float = 0.0
    R: float = 0.0


def term_avar(params, tau):
    """Variance of each term, shape (5, len(tau)) in (deg/h)^2, in the order of TERMS
    (NumPy in, NumPy out; JAX in, JAX out: :mod:`fogbayes.support.xp`)."""
    xp = namespace(params, tau)
    tau = xp.asarray(tau, dtype=float)
    return xp.stack([_A_PER_P2[t] * xp.asarray(p, dtype=float) ** 2 * tau ** POWERS[t]
                     for t, p in zip(TERMS, params)])


def avar(params, tau):
    """Five-term Allan variance sigma^2(tau) in (deg/h)^2.

    Example:
        >>> float(avar(AllanParams(N=1.0), 3600.0))  # N deg/sqrt(h) reads at tau = 1 h
        1.0
    """
    return term_avar(params, tau).sum(axis=0)


def adev(params, tau):
    """Five-term Allan deviation sigma(tau) in deg/h."""
    v = avar(params, tau)
    return namespace(v).sqrt(v)


def variance_coefficients(params):
    """a_n of sigma^2 = sum_n a_n tau^n (n = -2..2), tau in s, sigma in deg/h."""
    xp = namespace(params)
    return xp.stack([_A_PER_P2[t] * xp.asarray(p, dtype=float) ** 2
                     for t, p in zip(TERMS, params)])


def params_from_variance_coefficients(a) -> AllanParams:
    """Inverse of :func:`variance_coefficients` (negative a_n give 0)."""
    return AllanParams(*[math.sqrt(max(float(x), 0.0) / _A_PER_P2[t]) for t, x in zip(TERMS, a)])


def params_from_coefficients(C) -> AllanParams:
    """Paper 002's conversions from its C_n (n = -2..2, sigma^2 = sum C_n^2 tau^n).

    Example (the paper's reported fit):
        >>> p = params_from_coefficients([1.1754e-5, 1.0228e-2, 3.835e-3, 1.196e-3, 1.827e-4])
        >>> [float(f"{v:.4g}") for v in p]
        [6.786e-06, 0.0001705, 0.005776, 0.1243, 0.9302]
    """
    c_q, c_n, c_b, c_k, c_r = (float(c) for c in C)
    return AllanParams(Q=c_q / math.sqrt(3.0), N=c_n / 60.0, B=c_b / 0.664,
                       K=60.0 * math.sqrt(3.0) * c_k, R=3600.0 * math.sqrt(2.0) * c_r)


def coefficients_from_params(params) -> tuple[float, ...]:
    """Paper 002's C_n from canonical parameters (inverse of :func:`params_from_coefficients`)."""
    p = AllanParams(*params)
    return (math.sqrt(3.0) * p.Q, 60.0 * p.N, 0.664 * p.B, p.K / (60.0 * math.sqrt(3.0)),
            p.R / (3600.0 * math.sqrt(2.0)))


def markov_avar(tau, *, sigma, tau_c):
    """First-order Gauss-Markov term (paper 002 table 1), sigma deg/h, tau_c s."""
    xp = namespace(tau, sigma, tau_c)
    tau = xp.asarray(tau, dtype=float)
    x = tau / tau_c
    qt2 = 2.0 * sigma**2 * tau_c  # (q_c T_c)^2 with q_c^2 = 2 sigma^2 / T_c
    # 1 - (3 - 4 e^-x + e^-2x) / (2x), written with expm1 so small x does not cancel
    inner = 1.0 - (-4.0 * xp.expm1(-x) + xp.expm1(-2.0 * x)) / (2.0 * x)
    return qt2 / tau * inner


def sinusoid_avar(tau, *, amplitude, frequency):
    """Sinusoidal rate term Omega_0^2 (sin^2(pi f0 tau) / (pi f0 tau))^2 (IEEE 952 form)."""
    xp = namespace(tau, amplitude, frequency)
    x = math.pi * frequency * xp.asarray(tau, dtype=float)
    return amplitude**2 * (xp.sin(x) ** 2 / x) ** 2


def noise_scales(params, fs: float):
    """Scales of the power-law noises (quantization, white, flicker, rate random walk) in the
    sample units of :mod:`fogbayes.stats.allan_cov`, so that their expected AVARs are the
    Q, N, B and K terms (R, a deterministic ramp, adds to the mean only)."""
    xp = namespace(params)
    q, n, b, k = (xp.asarray(p, dtype=float) for p in tuple(params)[:4])
    return xp.stack([q**2 * fs**2, (60.0 * n) ** 2 * fs, b**2 / (2.0 * math.pi),
                     (k / 60.0) ** 2 / fs])


def ramp_avar(params, tau):
    """The rate-ramp term alone (deterministic: it shifts the mean, adds no variance)."""
    xp = namespace(params, tau)
    return _A_PER_P2["R"] * xp.asarray(tuple(params)[4], dtype=float) ** 2 * \
        xp.asarray(tau, dtype=float) ** 2
