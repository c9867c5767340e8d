"""Paper 000's composite static temperature model of a FOG, as array functions (NumPy on
NumPy input, JAX under jit/grad/vmap: :mod:`fogbayes.support.xp`).

U = S1(T) S2(W) W + U0(T) + U1(T) t = sum M_ij T^i W^(j+1) + sum c_i T^i + t sum d_i T^i
(eq. 8/14; T deg C, W deg/s, t s). :class:`FullParams` (linear) or :class:`ProductParams`
(M = a b^T, b_0 = 1). Centred and scaled: T' = (T - T_ref) / T_scale, W' = W / W_scale,
t' = t / t_scale, U = U_ref + U_scale [...]; :func:`to_raw` maps exactly to
:class:`RawCoefficients` (eqs. 15/16/12); ``PAPER_000`` holds the printed values.
"""

from __future__ import annotations

from math import comb
from typing import NamedTuple

import numpy as np

from ..errors import FogbayesError, ShapeError
from ..support.lazy import lazy_module
from ..support.xp import namespace

jnp = lazy_module("jax.numpy")  # at first use: reading the orders needs no JAX


class Orders(NamedTuple):
    """Polynomial orders: S1 in T, S2 in W (so U has powers W^1..W^(s2+1)), U0 and U1 in T."""

    s1: int
    s2: int
    u0: int
    u1: int

    def label(self) -> str:
        return f"{self.s1},{self.s2},{self.u0},{self.u1}"


#: The orders paper 000 settles on (eq. 12/13/16).
PAPER_ORDERS = Orders(2, 3, 2, 2)


class Scaling(NamedTuple):
    """Centring and scaling of the inputs and output (floats; a pytree, never static)."""

    T_ref: float
    T_scale: float
    W_scale: float
    t_scale: float
    U_ref: float
    U_scale: float


class FullParams(NamedTuple):
    """Linear parameterisation in scaled units: M' (s1+1, s2+1), c' (u0+1,), d' (u1+1,)."""

    M: jnp.ndarray
    c: jnp.ndarray
    d: jnp.ndarray


class ProductParams(NamedTuple):
    """Rank-1 form in scaled units: M' = a' [1, b'_1 .. b'_s2]^T; a' (s1+1,), b' (s2,)."""

    a: jnp.ndarray
    b: jnp.ndarray
    c: jnp.ndarray
    d: jnp.ndarray


class RawCoefficients(NamedTuple):
    """The paper's coefficients: M (eq. 15, rows T^i, columns W^j), c (eq. 16), d (eq. 12)."""

    M: np.ndarray
    c: np.ndarray
    d: np.ndarray


#: Paper 000's printed coefficients (eq. 15, 16, 12). Eq. 17 misprints M[0, 2] as
#: -7.9343e-7; eq. 15's -7.9343e-4 is the value that reproduces Tables 1-2 (docs/REFERENCE.md).
PAPER_000 = RawCoefficients(
    M=np.array([[3.9621e1, -5.9735e-4, -7.9343e-4, 7.1717e-8],
                [-1.3299e-2, 7.5276e-6, 5.5587e-7, -1.1835e-9],
                [2.5685e-5, 1.3955e-7, -9.9851e-9, -5.2857e-12]]),
    c=np.array([4.2774, 1.6725e-2, -7.3068e-4]),
    d=np.array([1.4774e-4, 7.2173e-6, -2.0527e-7]),
)


#: A compensated sample counts as solved when |w P(w) - y| <= RESID_ABS + RESID_REL |y|
#: (scaled units, y ~ 1 at full scale): 1e3 x above float32 rounding, far below a failed
#: solve. Shared by the XLA program and the compiled loop (fogbayes.composite.compensate).
RESID_ABS, RESID_REL = 1e-6, 1e-5


class OrdersError(FogbayesError):
    """An order string or order value the composite model cannot use."""


def parse_orders(text: str | Orders | None, default: Orders = PAPER_ORDERS) -> Orders:
    """``"s1,s2,u0,u1"`` (e.g. ``"2,3,2,2"``) -> :class:`Orders`; None gives ``default``."""
    if text is None:
        return default
    if isinstance(text, Orders):
        vals = tuple(text)
    else:
        parts = [p.strip() for p in str(text).split(",")]
        try:
            vals = tuple(int(p) for p in parts)
        except ValueError:
            vals = ()
    if len(vals) != 4 or any(v < 0 or v > 6 for v in vals):
        raise OrdersError(f"orders {text!r} are not four integers 0..6", column="orders",
                          fix="give --orders s1,s2,u0,u1, e.g. 2,3,2,2 (paper 000)")
    return Orders(*vals)


#: What ``u1`` reads in the orders grammar when the model has no drift term U1(T) t.
NO_DRIFT = "-"


def read_orders(text: str) -> tuple[int, int, int, int | None]:
    """The composite orders grammar of every command: ``"s1,s2,u0[,u1]"``.

    Three values set u1 = u0 (paper 000's rule); ``u1`` = ``-`` means no drift term
    U1(T) t at all (u1 = 0 is a constant U1, not none). Returns (s1, s2, u0, u1 or None).
    """
    parts = [p.strip() for p in str(text).split(",")]
    if len(parts) == 3:
        parts.append(parts[2])
    u1 = None if len(parts) == 4 and parts[3] == NO_DRIFT else parts[3:]
    try:
        vals = tuple(int(p) for p in parts[:3]) + ((int(u1[0]),) if u1 else ())
    except ValueError:
        vals = ()
    if len(parts) != 4 or len(vals) != (4 if u1 else 3) or any(v < 0 or v > 6 for v in vals):
        raise OrdersError(f"orders {text!r} are not s1,s2,u0[,u1] (integers 0..6; u1 may "
                          f"be {NO_DRIFT!r})", column="orders",
                          fix="e.g. 2,3,2,2 (paper 000), 2,3,2 (u1 = u0) or 0,0,2,- (no "
                              "U1(T) t drift term)")
    return vals if u1 else vals + (None,)


def orders_of(params: FullParams | ProductParams | RawCoefficients) -> Orders:
    """The orders encoded in the parameter shapes."""
    if isinstance(params, ProductParams):
        s1, s2 = params.a.shape[-1] - 1, params.b.shape[-1]
    else:
        s1, s2 = params.M.shape[-2] - 1, params.M.shape[-1] - 1
    return Orders(s1, s2, params.c.shape[-1] - 1, params.d.shape[-1] - 1)


# ------------------------------------------------------------------------------ evaluation
def _horner(coef, x):
    """sum_k coef[..., k] x^k by Horner's rule (order static, unrolled at trace time;
    NumPy on NumPy input, :mod:`fogbayes.support.xp`)."""
    out = coef[..., -1] * namespace(coef, x).ones_like(x)
    for k in range(coef.shape[-1] - 2, -1, -1):
        out = out * x + coef[..., k]
    return out


def scale_inputs(sc: Scaling, T, W, t):
    """(T', W', t') in the dtype of the inputs (centring first keeps float32 usable)."""
    return (T - sc.T_ref) / sc.T_scale, W / sc.W_scale, t / sc.t_scale


def product_to_full(p: ProductParams) -> FullParams:
    """M' = a' outer [1, b'] (the rank-1 scale factor as a full matrix)."""
    xp = namespace(p.a, p.b)
    b = xp.concatenate([xp.ones(p.b.shape[:-1] + (1,), p.a.dtype), p.b], axis=-1)
    return FullParams(p.a[..., :, None] * b[..., None, :], p.c, p.d)


def predict_scaled(p: FullParams, Tp, Wp, tp):
    """U' (scaled output) at scaled inputs; broadcasts over samples (NumPy on NumPy input:
    :func:`fogbayes.composite.compensate.choose_iterations` evaluates a grid once a call,
    where eager JAX compiled a program per operation, 0.6 s)."""
    xp = namespace(p, Tp, Wp, tp)
    S = xp.stack([_horner(p.M[:, j], Tp) for j in range(p.M.shape[1])], axis=-1)
    sw = _horner(S, Wp) * Wp
    return sw + _horner(p.c, Tp) + tp * _horner(p.d, Tp)


def predict(p: FullParams | ProductParams, sc: Scaling, T, W, t):
    """U = S1(T) S2(W) W + U0(T) + U1(T) t in output units (eq. 14), for scaled params."""
    if isinstance(p, ProductParams):
        p = product_to_full(p)
    Tp, Wp, tp = scale_inputs(sc, T, W, t)
    return sc.U_ref + sc.U_scale * predict_scaled(p, Tp, Wp, tp)


def raw_predict(raw: RawCoefficients, T, W, t):
    """Eq. 14 evaluated directly from raw coefficients (NumPy, float64; display/checks)."""
    T, W, t = (np.asarray(v, dtype=float) for v in (T, W, t))
    M, c, d = (np.asarray(v, dtype=float) for v in raw)
    pw = np.stack([W ** (j + 1) for j in range(M.shape[1])], axis=-1)
    pt = np.stack([T ** i for i in range(M.shape[0])], axis=-1)
    scale = np.einsum("...i,ij,...j->...", pt, M, pw)
    u0 = sum(c[i] * T ** i for i in range(c.size))
    u1 = sum(d[i] * T ** i for i in range(d.size))
    return scale + u0 + u1 * t


def design_matrix(orders: Orders, sc: Scaling, T, W, t) -> np.ndarray:
    """X (n, p) with U' = X theta for theta = pack(FullParams); columns in pack order.

    NumPy, float64: the order searches build one per candidate, and eager JAX compiled a
    small program for every column count."""
    Tp, Wp, tp = scale_inputs(sc, *(np.asarray(v, dtype=float) for v in (T, W, t)))
    tpow = [Tp ** i for i in range(max(orders.s1, orders.u0, orders.u1) + 1)]
    cols = [tpow[i] * Wp ** (j + 1) for i in range(orders.s1 + 1) for j in range(orders.s2 + 1)]
    cols += [tpow[i] for i in range(orders.u0 + 1)]
    cols += [tp * tpow[i] for i in range(orders.u1 + 1)]
    return np.stack(cols, axis=-1)


def n_params(orders: Orders) -> int:
    return (orders.s1 + 1) * (orders.s2 + 1) + orders.u0 + 1 + orders.u1 + 1


def pack(p: FullParams):
    """FullParams -> flat theta (M row-major, then c, then d); leading batch axes kept."""
    lead = p.M.shape[:-2]
    xp = namespace(p.M, p.c, p.d)
    return xp.concatenate([p.M.reshape(lead + (-1,)), p.c, p.d], axis=-1)


def unpack(theta, orders: Orders) -> FullParams:
    """Inverse of :func:`pack`."""
    nm = (orders.s1 + 1) * (orders.s2 + 1)
    lead = theta.shape[:-1]
    M = theta[..., :nm].reshape(lead + (orders.s1 + 1, orders.s2 + 1))
    return FullParams(M, theta[..., nm:nm + orders.u0 + 1], theta[..., nm + orders.u0 + 1:])


def param_labels(orders: Orders) -> list[str]:
    """Names of the raw coefficients in pack order, e.g. ``M[1,2]`` = coefficient of T W^3."""
    out = [f"M[{i},{j}]" for i in range(orders.s1 + 1) for j in range(orders.s2 + 1)]
    out += [f"c[{i}]" for i in range(orders.u0 + 1)]
    return out + [f"d[{i}]" for i in range(orders.u1 + 1)]


# ------------------------------------------------------------------------------ raw <-> scaled
def _shift_matrix(order: int, T_ref: float, T_scale: float) -> np.ndarray:
    """P (order+1, order+1) with raw = P @ scaled for polynomials in T' = (T - T_ref)/T_scale.

    (T - T_ref)^i / T_scale^i = sum_k C(i, k) T^k (-T_ref)^(i-k) / T_scale^i.
    """
    P = np.zeros((order + 1, order + 1))
    for i in range(order + 1):
        for k in range(i + 1):
            P[k, i] = comb(i, k) * (-T_ref) ** (i - k) / T_scale ** i
    return P


def raw_map(orders: Orders, sc: Scaling) -> np.ndarray:
    """J (p, p) with theta_raw = J @ theta_scaled + offset (pack order); exact, linear."""
    PM = _shift_matrix(orders.s1, sc.T_ref, sc.T_scale)
    wcol = np.array([sc.U_scale / sc.W_scale ** (j + 1) for j in range(orders.s2 + 1)])
    JM = np.kron(PM, np.diag(wcol))  # row-major M: index i*(s2+1)+j
    Jc = sc.U_scale * _shift_matrix(orders.u0, sc.T_ref, sc.T_scale)
    Jd = sc.U_scale / sc.t_scale * _shift_matrix(orders.u1, sc.T_ref, sc.T_scale)
    n = n_params(orders)
    J = np.zeros((n, n))
    a, b = JM.shape[0], JM.shape[0] + Jc.shape[0]
    J[:a, :a], J[a:b, a:b], J[b:, b:] = JM, Jc, Jd
    return J


def raw_offset(orders: Orders, sc: Scaling) -> np.ndarray:
    """The constant part of the raw map: U_ref goes into c_0."""
    off = np.zeros(n_params(orders))
    off[(orders.s1 + 1) * (orders.s2 + 1)] = sc.U_ref
    return off


def to_raw(p: FullParams | ProductParams, sc: Scaling) -> RawCoefficients:
    """Scaled parameters -> the paper's raw coefficients (NumPy float64; batch axes kept)."""
    if isinstance(p, ProductParams):
        p = product_to_full(p)
    orders = orders_of(p)
    theta = pack(FullParams(*(np.asarray(v, dtype=float) for v in p)))
    raw = theta @ raw_map(orders, sc).T + raw_offset(orders, sc)
    return RawCoefficients(*unpack(raw, orders))


def from_raw(raw: RawCoefficients, sc: Scaling) -> FullParams:
    """Raw coefficients -> scaled :class:`FullParams` (inverse of :func:`to_raw`)."""
    M, c, d = (np.asarray(v, dtype=float) for v in raw)
    if M.ndim != 2 or c.ndim != 1 or d.ndim != 1:
        raise ShapeError("raw coefficients must be M (rows T^i, columns W^j), c and d vectors",
                         column="params", fix="give M as a 2-D array and c, d as 1-D arrays")
    orders = Orders(M.shape[0] - 1, M.shape[1] - 1, c.size - 1, d.size - 1)
    theta_raw = np.concatenate([M.ravel(), c, d]) - raw_offset(orders, sc)
    theta = np.linalg.solve(raw_map(orders, sc), theta_raw)
    return unpack(jnp.asarray(theta), orders)


def raw_covariance(cov_scaled, orders: Orders, sc: Scaling) -> np.ndarray:
    """Covariance of the raw coefficients: J cov J^T (pack order)."""
    J = raw_map(orders, sc)
    return J @ np.asarray(cov_scaled, dtype=float) @ J.T


def full_to_product(p: FullParams) -> ProductParams:
    """Best rank-1 approximation of M' (SVD), normalised so that b'_0 = 1.

    Exact when M' has rank 1; otherwise the nearest product in the Frobenius norm of the
    scaled matrix (a starting point for the bilinear fit, not a conversion).
    """
    M = np.asarray(p.M, dtype=float)
    u, s, vt = np.linalg.svd(M)
    a, b = u[:, 0] * s[0], vt[0]
    if abs(b[0]) < 1e-12 * np.max(np.abs(b)):
        raise ShapeError("the scale factor at zero rate is 0: S2 cannot be normalised",
                         column="params", fix="use the full-matrix parameterisation")
    return ProductParams(jnp.asarray(a * b[0]), jnp.asarray(b[1:] / b[0]), p.c, p.d)
