"""Joint least-squares fits of the composite model (paper 000) on all samples.

Full matrix: y' = X(T, W, t) theta + e by ``lstsq``, cov = s^2 (X'X)^-1; ``noise="ar<p>"``:
feasible GLS, phi by Yule-Walker pooled within cells, prewhitening inside each cell, iterated.
Rank-1 product M' = a [1, b]^T: optax L-BFGS in one ``lax.scan`` from the best rank-1
approximation, cov = s^2 (J'J)^-1 (Gauss-Newton).
"""

from __future__ import annotations

import re
from functools import partial
from typing import NamedTuple

import numpy as np

from ..errors import FogbayesError, TooShortError
from ..support.lazy import lazy_module
from ..support.programs import program
from .cells import RateData
from .model import (FullParams, Orders, ProductParams, Scaling, design_matrix,
                    full_to_product, n_params, pack, product_to_full, unpack)


# imported at first use: the closed-form fits (the workflow's default) need no JAX
jax = lazy_module("jax")
jnp = lazy_module("jax.numpy")


class LsqFit(NamedTuple):
    """A full-matrix least-squares fit (scaled units; raw ones by ``composite.to_raw``)."""

    params: FullParams
    scaling: Scaling
    orders: Orders
    cov: np.ndarray  # (p, p) covariance of pack(params)
    sigma: float  # innovation std of the noise, output units
    ar: np.ndarray  # AR coefficients of the noise (empty: white)
    dof: int  # residual degrees of freedom
    n: int
    rms: float  # RMS of the (not prewhitened) residuals, output units
    converged: bool
    lam: float = 0.0  # cell-offset variance / white variance ("cells" noise)
    rho: float = 0.0  # correlation of consecutive cell offsets ("cells" noise)


class ProductFit(NamedTuple):
    """A rank-1 product fit by optax (scaled units)."""

    params: ProductParams
    scaling: Scaling
    orders: Orders
    cov: np.ndarray  # Gauss-Newton covariance of (a', b', c', d')
    sigma: float
    loss: float  # final mean squared scaled residual
    grad_norm: float
    steps: int
    converged: bool


class NoiseSpecError(FogbayesError):
    """A noise model the least-squares fit does not know."""


def parse_noise(noise: str) -> int:
    """``"white"`` -> 0, ``"ar1"``/``"ar(2)"``... -> p, ``"cells"`` -> -1."""
    if noise == "white":
        return 0
    if noise == "cells":
        return -1
    m = re.fullmatch(r"ar\(?(\d)\)?", str(noise).lower().replace(" ", ""))
    if not m or int(m.group(1)) < 1:
        raise NoiseSpecError(f"unknown noise model {noise!r}", column="noise",
                             fix="use 'white', 'cells' or 'ar1' ... 'ar9'")
    return int(m.group(1))


def default_scaling(data: RateData) -> Scaling:
    """Mid-range/half-range for T, max |W|, max t, and mean/max-deviation for U."""
    lo, hi = float(np.min(data.T)), float(np.max(data.T))
    half = (hi - lo) / 2
    u_ref = float(np.mean(data.U))
    u_dev = float(np.max(np.abs(data.U - u_ref)))
    return Scaling(T_ref=(lo + hi) / 2, T_scale=half if half > 0 else 1.0,
                   W_scale=float(np.max(np.abs(data.W))) or 1.0,
                   t_scale=float(np.max(np.abs(data.t))) or 1.0,
                   U_ref=u_ref, U_scale=u_dev if u_dev > 0 else 1.0)


def _xy(data: RateData, orders: Orders, sc: Scaling):
    X = np.asarray(design_matrix(orders, sc, data.T, data.W, data.t))
    y = (np.asarray(data.U) - sc.U_ref) / sc.U_scale
    return X, y


def _check_size(n: int, p: int, orders: Orders):
    if n <= p:
        raise TooShortError(f"orders {orders.label()} have {p} coefficients but only {n} "
                            "samples", column="orders", fix="record more cells or lower the orders")


def yule_walker_cells(r: np.ndarray, cell: np.ndarray, p: int) -> np.ndarray:
    """AR(p) coefficients from autocovariances pooled within cells (lags never cross cells)."""
    same = lambda k: cell[k:] == cell[:-k]  # noqa: E731
    g = [np.dot(r, r) / r.size] + [np.dot(r[k:][same(k)], r[:-k][same(k)]) / r.size
                                   for k in range(1, p + 1)]
    G = np.array([[g[abs(i - j)] for j in range(p)] for i in range(p)])
    phi = np.linalg.solve(G, np.array(g[1:]))
    return phi


def prewhiten(x: np.ndarray, cell: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """x_t - sum phi_i x_{t-i} inside each cell; rows without p in-cell predecessors dropped."""
    p = phi.size
    keep = np.ones(cell.size, bool)
    keep[:p] = False
    out = x[p:].copy() if p else x.copy()
    for i in range(1, p + 1):
        keep[p:] &= cell[p:] == cell[p - i:cell.size - i]
        out = out - phi[i - 1] * x[p - i:x.shape[0] - i]
    return out[keep[p:]] if p else out


def fit_joint(data: RateData, orders: Orders, *, scaling: Scaling | None = None,
              noise: str = "white", iterations: int = 3) -> LsqFit:
    """Closed-form least squares of the full-matrix model on all in-cell samples.

    Args:
        data: from :func:`fogbayes.composite.cells.rate_data`.
        orders: the model orders.
        scaling: default :func:`default_scaling` of the data.
        noise: ``"white"`` (OLS), ``"ar<p>"`` (feasible GLS, AR(p) within cells) or
            ``"cells"`` (white + AR(1)-across-cells offsets by REML, the default of the
            workflow: see :mod:`fogbayes.composite.noise`).
        iterations: FGLS passes (phi from the previous pass's residuals).
    """
    sc = scaling or default_scaling(data)
    p_ar = parse_noise(noise)
    X, y = _xy(data, orders, sc)
    p = n_params(orders)
    _check_size(y.size, p, orders)
    if p_ar < 0:
        from .noise import cell_stats, fit_cell_noise

        cn = fit_cell_noise(cell_stats(X, y, data.cell, data.time))
        rms = float(np.sqrt(np.mean((y - X @ cn.theta) ** 2))) * sc.U_scale
        return LsqFit(unpack(np.asarray(cn.theta), orders), sc, orders, cn.cov,
                      float(np.sqrt(cn.s2)) * sc.U_scale, np.zeros(0), cn.dof, int(y.size), rms,
                      bool(np.all(np.isfinite(cn.cov))), cn.lam, cn.rho)
    theta = np.linalg.lstsq(X, y, rcond=None)[0]
    phi = np.zeros(0)
    Xw, yw = X, y
    for _ in range(iterations if p_ar else 0):
        phi = yule_walker_cells(y - X @ theta, data.cell, p_ar)
        Xw, yw = prewhiten(X, data.cell, phi), prewhiten(y, data.cell, phi)
        theta = np.linalg.lstsq(Xw, yw, rcond=None)[0]
    resid = yw - Xw @ theta
    dof = yw.size - p
    s2 = float(resid @ resid) / dof
    cov = s2 * np.linalg.inv(Xw.T @ Xw)
    rms = float(np.sqrt(np.mean((y - X @ theta) ** 2))) * sc.U_scale
    ok = bool(np.all(np.isfinite(theta)) and np.all(np.isfinite(cov)) and
              (p_ar == 0 or np.all(np.abs(np.roots(np.r_[1.0, -phi])) < 1)))
    return LsqFit(unpack(np.asarray(theta), orders), sc, orders, cov,
                  float(np.sqrt(s2)) * sc.U_scale, phi, int(dof), int(y.size), rms, ok)


# ------------------------------------------------------------------------------ optax path
def _product_from_vector(v, orders: Orders) -> ProductParams:
    a_n, b_n, c_n = orders.s1 + 1, orders.s2, orders.u0 + 1
    return ProductParams(v[:a_n], v[a_n:a_n + b_n], v[a_n + b_n:a_n + b_n + c_n],
                         v[a_n + b_n + c_n:])


def _vector_to_theta(v, orders: Orders, form: str):
    if form == "full":
        return v
    return pack(product_to_full(_product_from_vector(v, orders)))


@partial(program, static_argnames=("orders", "form", "steps"))
def _lbfgs(v0, X, y, *, orders: Orders, form: str, steps: int):
    """L-BFGS on 0.5 mean((y - X theta(v))^2), ``steps`` iterations in one lax.scan."""
    def loss(v):
        r = y - X @ _vector_to_theta(v, orders, form)
        return 0.5 * jnp.mean(r * r)

    from ..inference.lsq import lbfgs_scan  # optax: imported with JAX

    v, trace = lbfgs_scan(loss, v0, steps=steps)
    return v, loss(v), jnp.linalg.norm(jax.grad(loss)(v)), trace


def fit_optax(data: RateData, orders: Orders, *, form: str = "product",
              scaling: Scaling | None = None, init: FullParams | None = None,
              steps: int = 300, gtol: float = 1e-9) -> ProductFit | LsqFit:
    """Least squares by optax L-BFGS, for the rank-1 ``"product"`` or the ``"full"`` form.

    ``init`` defaults to the closed-form full fit (its rank-1 part for the product form),
    so the bilinear problem starts inside the right basin. Convergence: gradient norm of
    the mean-squared loss below ``gtol`` (scaled units).
    """
    sc = scaling or default_scaling(data)
    X, y = _xy(data, orders, sc)
    if init is None:
        init = fit_joint(data, orders, scaling=sc).params
    if form == "full":
        v0 = pack(init)
    elif form == "product":
        v0 = jnp.concatenate(list(full_to_product(init)))
    else:
        raise NoiseSpecError(f"unknown form {form!r}", column="form", fix="use 'product' or 'full'")
    _check_size(y.size, v0.size, orders)
    v, loss, gnorm, _ = _lbfgs(v0, jnp.asarray(X), jnp.asarray(y), orders=orders, form=form,
                               steps=steps)
    J = np.asarray(X @ jax.jacfwd(_vector_to_theta)(v, orders, form))
    dof = y.size - v.size
    s2 = 2.0 * float(loss) * y.size / dof
    cov = s2 * np.linalg.pinv(J.T @ J)
    ok = bool(np.isfinite(loss) and float(gnorm) < gtol)
    sigma = float(np.sqrt(s2)) * sc.U_scale
    if form == "full":
        return LsqFit(unpack(v, orders), sc, orders, cov, sigma, np.zeros(0), dof, y.size,
                      float(np.sqrt(2 * loss)) * sc.U_scale, ok)
    return ProductFit(_product_from_vector(v, orders), sc, orders, cov, sigma, float(loss),
                      float(gnorm), steps, ok)
