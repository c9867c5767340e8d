"""Deterministic gyro error effects as plain functions (rate error in deg/h unless stated).

Covariates: t time (s), T a temperature channel (deg C), T1/T2 two channels, dTdt the
temperature rate in deg C/min, omega the input rate in deg/s. The scale-factor effects
return the output error in deg/h for a gyro whose nominal scale is 3600 (deg/h)/(deg/s).
Every function is vectorised over its array arguments and has its formula in the docstring.
"""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np

from .profiles import first_order_lag


def temperature_order(T, *, coeffs: Sequence[float], T_ref: float = 0.0):
    """Bias polynomial in temperature: b = sum_i c_i (T - T_ref)^i, i = 0 .. len(coeffs)-1."""
    x = np.asarray(T, dtype=float) - T_ref
    return np.polynomial.polynomial.polyval(x, np.asarray(coeffs, dtype=float))


def temperature_rate(dTdt, *, coeff: float):
    """Shupe term: b = k dT/dt, k in (deg/h) / (deg C/min), dT/dt in deg C/min."""
    return coeff * np.asarray(dTdt, dtype=float)


def temperature_gradient(T1, T2, *, coeff: float):
    """Gradient between two channels (e.g. inner/outer coil): b = k (T2 - T1), k deg/h/deg C."""
    return coeff * (np.asarray(T2, dtype=float) - np.asarray(T1, dtype=float))


def thermal_hysteresis(dTdt, *, size: float, rate_scale: float = 0.05,
                       width: float | None = None, T=None):
    """Heating vs cooling offset: b = (h/2) tanh(dT/dt / r0).

    +h/2 while heating, -h/2 while cooling, 0 at constant temperature, switching smoothly
    over |dT/dt| ~ r0 (deg C/min). So the bias-vs-T curve is h higher heating than cooling.

    With ``width`` w (deg C) the memory form instead: b = (h/2) (T - P) / (w/2), P the play
    operator (P follows T once T is w/2 past it; P_0 = T_0): +h/2 after heating, -h/2 after
    cooling, held through a soak at the value the last ramp left.
    """
    if width is None:
        return 0.5 * size * np.tanh(np.asarray(dTdt, dtype=float) / rate_scale)
    T = np.asarray(T, dtype=float)
    h, P, y = 0.5 * width, np.empty_like(T), float(T[0])
    for i, x in enumerate(T):
        y = min(max(y, x - h), x + h)
        P[i] = y
    return 0.5 * size * (T - P) / h


def thermal_lag(t, T, *, coeff: float, tau: float, T_ref: float = 0.0):
    """Bias driven by a lagged temperature: b = k (T_lag - T_ref), tau dT_lag/dt = T - T_lag.

    T_lag starts in equilibrium with T (see :func:`profiles.first_order_lag`).
    """
    return coeff * (first_order_lag(t, T, tau) - T_ref)


def time_drift(t, *, slope: float = 0.0, amplitude: float = 0.0, tau: float = 3600.0):
    """Drift and warm-up: b = s t / 3600 + A (1 - exp(-t / tau)).

    s deg/h per hour, A deg/h, tau s, t from the start of the recording.
    """
    t = np.asarray(t, dtype=float)
    return slope * t / 3600.0 - amplitude * np.expm1(-t / tau)


def periodic(t, *, amplitude: float, frequency: float, phase: float = 0.0):
    """Periodic error: b = A sin(2 pi f t + phase), f in Hz."""
    return amplitude * np.sin(2.0 * math.pi * frequency * np.asarray(t, dtype=float) + phase)


def step(t, *, time: float, size: float):
    """Bias step: b = size for t >= time, else 0."""
    return np.where(np.asarray(t, dtype=float) >= time, float(size), 0.0)


def scale_factor_nonlinearity(omega, *, k2: float = 0.0, k3: float = 0.0):
    """Scale-factor nonlinearity: relative scale error e = k2 omega + k3 omega^2, so the
    output error is 3600 omega e = 3600 (k2 omega^2 + k3 omega^3) deg/h
    (k2 in 1/(deg/s), k3 in 1/(deg/s)^2)."""
    w = np.asarray(omega, dtype=float)
    return 3600.0 * (k2 * w**2 + k3 * w**3)


def scale_factor_asymmetry(omega, *, asymmetry: float):
    """Different scale for omega > 0 and omega < 0: e = +a/2 (omega > 0), -a/2 (omega < 0),
    output error 3600 omega e = 1800 a |omega| deg/h (a dimensionless, e.g. 1e-4 = 100 ppm)."""
    return 1800.0 * asymmetry * np.abs(np.asarray(omega, dtype=float))


def scale_factor_temperature(omega, T, *, coeff: float, T_ref: float = 0.0):
    """Scale factor linear in temperature: e = k (T - T_ref) (k per deg C), output error
    3600 omega k (T - T_ref) deg/h."""
    return 3600.0 * coeff * np.asarray(omega, dtype=float) * (np.asarray(T, dtype=float) - T_ref)


# -- paper 000: the composite static model of the VG951 (output in volts) ---------------
#: eq. 15: M[i, j] = a_i b_j, rows T^0..T^2, columns Omega^0..Omega^3 (V per deg/s).
PAPER000_M = np.array([
    [3.9621e1, -5.9735e-4, -7.9343e-4, 7.1717e-8],
    [-1.3299e-2, 7.5276e-6, 5.5587e-7, -1.1835e-9],
    [2.5685e-5, 1.3955e-7, -9.9851e-9, -5.2857e-12],
])
#: eq. 16: U0(T) = c0 + c1 T + c2 T^2 (V).
PAPER000_U0 = np.array([4.2774, 1.6725e-2, -7.3068e-4])
#: eq. 12: U1(T) = d0 + d1 T + d2 T^2 (V/s).
PAPER000_U1 = np.array([1.4774e-4, 7.2173e-6, -2.0527e-7])


def paper000_scale(T, omega, *, M=PAPER000_M):
    """S1(T) S2(omega) omega = [1 T T^2] M [1 omega omega^2 omega^3]^T omega (V)."""
    T, w = np.asarray(T, dtype=float), np.asarray(omega, dtype=float)
    M = np.asarray(M, dtype=float)
    total = np.zeros(np.broadcast(T, w).shape)
    for i in range(M.shape[0]):  # written term by term from the raw coefficients on purpose:
        for j in range(M.shape[1]):  # this is the independent truth for the composite model
            total = total + M[i, j] * T**i * w**j
    return total * w


def paper000_bias(T, *, c=PAPER000_U0):
    """U0(T) = c0 + c1 T + c2 T^2 (V)."""
    T = np.asarray(T, dtype=float)
    return c[0] + c[1] * T + c[2] * T**2


def paper000_drift(T, t, *, d=PAPER000_U1):
    """U1(T) t = (d0 + d1 T + d2 T^2) t (V), t the operating time (s)."""
    T = np.asarray(T, dtype=float)
    return (d[0] + d[1] * T + d[2] * T**2) * np.asarray(t, dtype=float)


def paper000_output(T, omega, t, *, M=PAPER000_M, c=PAPER000_U0, d=PAPER000_U1):
    """Paper 000 eq. 14/17: U = [1 T T^2] M [1 w w^2 w^3]^T w + U0(T) + U1(T) t (V)."""
    return paper000_scale(T, omega, M=M) + paper000_bias(T, c=c) + paper000_drift(T, t, d=d)


def paper000_linear_scale(T, *, M=PAPER000_M):
    """The paper's initial scale S0(T) = a0 b0 + a1 b0 T + a2 b0 T^2 (first column of M)."""
    T = np.asarray(T, dtype=float)
    return M[0, 0] + M[1, 0] * T + M[2, 0] * T**2


# -- paper 004: bias vs temperature and temperature rate ---------------------------------
def paper004_bias(T, dTdt, *, c: Sequence[float] = (0.0, 0.0, 0.0),
                  d: Sequence[float] = (0.0, 0.0), cross: float = 0.0, T_ref: float = 0.0):
    """Order-2 bias model: b = c0 + c1 x + c2 x^2 + d1 r + d2 r^2 + e x r,
    x = T - T_ref (deg C), r = dT/dt (deg C/min), b in deg/h."""
    x = np.asarray(T, dtype=float) - T_ref
    r = np.asarray(dTdt, dtype=float)
    return c[0] + c[1] * x + c[2] * x**2 + d[0] * r + d[1] * r**2 + cross * x * r
