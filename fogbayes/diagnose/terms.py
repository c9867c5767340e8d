"""Model terms: every column a base model or a candidate effect can put in a design matrix.

A :class:`Term` is data (``kind`` + JSON-able ``params``); :func:`columns` evaluates it on
:class:`~fogbayes.diagnose.covariates.Covariates` at any resolution (samples or blocks), so
the same term is screened on blocks, fitted on block means of its per-sample columns and
used to compensate every sample. All columns are centred/scaled to O(1)::

    intercept            1
    tpoly                ((T_c - centre) / scale)^k, k in powers         (bias polynomial)
    rate                 (dT/dt) / scale                                 (deg C/min)
    rate_poly            ((dT/dt) / scale)^k                             (paper 004 rate terms)
    gradient             (T_b - T_a) / scale                             (two channels)
    hysteresis           tanh((dT/dt) / r0)                              (+heating / -cooling)
    lag                  (L_tau[T_0] - centre) / scale, tau dL/dt = T - L (first-order lag)
    drift_lin            t / duration
    drift_exp            exp(-t / tau)                                   (warm-up)
    periodic             sin(2 pi f t), cos(2 pi f t)
    step                 1[t >= time]
    omega_poly           (W / scale)^k                                   (rate table)
    omega_abs            |W| / scale
    omega_tpoly          (W / scale)^m ((T - centre) / scale_T)^k        (m = wpower, default 1)
    drift_tpoly          (t / scale_t) ((T - centre) / scale)^k         (paper 000's U1(T) t,
                         t the operating time since the last input-rate step if known)
"""

from __future__ import annotations

from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from .covariates import Covariates


class Term(NamedTuple):
    """One model term: ``kind`` (see module doc) and its JSON-able parameters."""

    kind: str
    params: dict[str, Any]

    @property
    def n_cols(self) -> int:
        if self.kind in ("tpoly", "rate_poly", "omega_poly", "omega_tpoly", "drift_tpoly"):
            return len(self.params["powers"])
        return 2 if self.kind == "periodic" else 1


@jax.jit
def _lag_scan(a: jax.Array, b: jax.Array) -> jax.Array:
    """y_k = a_k y_{k-1} + b_k (y_{-1} = 0) by an associative scan (O(n log n), no loop)."""
    def comb(x, y):
        return y[0] * x[0], y[0] * x[1] + y[1]
    return jax.lax.associative_scan(comb, (a, b))[1]


def first_order_lag(t: np.ndarray, u: np.ndarray, tau: float) -> np.ndarray:
    """tau dL/dt = u - L, L(t_0) = u(t_0), exact for u linear between samples (any spacing).

    L_k = a_k L_{k-1} + (1 - c_k) u_k + (c_k - a_k) u_{k-1},  a_k = exp(-h_k/tau),
    c_k = tau (1 - a_k) / h_k. Uniform steps: ``scipy.signal.lfilter`` (no compilation);
    otherwise the time-varying recursion by an associative scan.
    """
    from scipy.signal import lfilter

    t, u = np.asarray(t, float), np.asarray(u, float)
    if tau <= 0 or u.size < 2:
        return u.copy()
    h = np.maximum(np.diff(t), 1e-12)
    if np.ptp(h) <= 1e-9 * h[0]:
        a = float(np.exp(-h[0] / tau))
        c = float(-tau * np.expm1(-h[0] / tau) / h[0])
        b = [1.0 - c, c - a]
        y, _ = lfilter(b, [1.0, -a], u, zi=[u[0] - b[0] * u[0]])
        return y
    a = np.exp(-h / tau)
    c = -tau * np.expm1(-h / tau) / h
    b = (1.0 - c) * u[1:] + (c - a) * u[:-1]
    a_all = np.concatenate([[0.0], a])
    b_all = np.concatenate([[u[0]], b])
    return np.asarray(_lag_scan(jnp.asarray(a_all), jnp.asarray(b_all)))


def _channel(cov: Covariates, name: str | int) -> np.ndarray:
    if isinstance(name, int):
        return cov.T[:, name]
    return cov.T[:, cov.names.index(name)]


def columns(term: Term, cov: Covariates) -> np.ndarray:
    """Evaluate ``term`` on ``cov`` -> (n, term.n_cols)."""
    k, p = term.kind, term.params
    n = cov.t.size
    if k == "intercept":
        return np.ones((n, 1))
    if k == "tpoly":
        z = (_channel(cov, p["channel"]) - p["centre"]) / p["scale"]
        return np.column_stack([z ** e for e in p["powers"]])
    if k == "rate":
        return (cov.Tdot / p["scale"])[:, None]
    if k == "rate_poly":
        z = cov.Tdot / p["scale"]
        return np.column_stack([z ** e for e in p["powers"]])
    if k == "gradient":
        return ((_channel(cov, p["b"]) - _channel(cov, p["a"])) / p["scale"])[:, None]
    if k == "hysteresis":
        return np.tanh(cov.Tdot / p["r0"])[:, None]
    if k == "lag":
        L = first_order_lag(cov.t, _channel(cov, p["channel"]), p["tau"])
        return ((L - p["centre"]) / p["scale"])[:, None]
    if k == "drift_lin":
        return (cov.t / p["duration"])[:, None]
    if k == "drift_exp":
        return np.exp(-cov.t / p["tau"])[:, None]
    if k == "periodic":
        ph = 2.0 * np.pi * p["frequency"] * cov.t
        return np.column_stack([np.sin(ph), np.cos(ph)])
    if k == "step":
        return (cov.t >= p["time"]).astype(float)[:, None]
    if k == "omega_poly":
        z = cov.omega / p["scale"]
        return np.column_stack([z ** e for e in p["powers"]])
    if k == "omega_abs":
        return (np.abs(cov.omega) / p["scale"])[:, None]
    if k == "omega_tpoly":
        z = (_channel(cov, p["channel"]) - p["centre"]) / p["t_scale"]
        wz = (cov.omega / p["scale"]) ** p.get("wpower", 1)
        return np.column_stack([wz * z ** e for e in p["powers"]])
    if k == "drift_tpoly":  # U1(T) t with t the operating time when the run has one
        z = (_channel(cov, p["channel"]) - p["centre"]) / p["scale"]
        tt = cov.op_time if cov.op_time is not None else cov.t
        return np.column_stack([tt / p["duration"] * z ** e for e in p["powers"]])
    raise ValueError(f"unknown term kind {k!r}")


def design(terms: list[Term], cov: Covariates) -> np.ndarray:
    """Columns of every term side by side (n, sum of n_cols)."""
    return np.column_stack([columns(tm, cov) for tm in terms])


def labels(term: Term) -> list[str]:
    """Readable names of a term's columns."""
    k, p = term.kind, term.params
    if k == "tpoly":
        return [f"T'^{e}" for e in p["powers"]]
    if k == "rate_poly":
        return [f"(dT/dt)'^{e}" for e in p["powers"]]
    if k == "omega_poly":
        return [f"W'^{e}" for e in p["powers"]]
    if k == "omega_tpoly":
        return [f"W' T'^{e}" for e in p["powers"]]
    if k == "drift_tpoly":
        return [f"t' T'^{e}" for e in p["powers"]]
    if k == "periodic":
        return ["sin", "cos"]
    return [k]
