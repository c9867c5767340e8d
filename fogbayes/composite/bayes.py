"""NumPyro posterior of the composite model (full matrix, scaled coefficients).

theta ~ N(0, prior_scale^2 I), y' = X theta + e, e ~ N(0, s^2 V(eta)), sigma ~ HalfNormal(1).
``noise``: ``"white"``; ``"ar<p>"`` (exact per-cell AR(p), phi by
:func:`fogbayes.models.arma.pacf_to_ar`, PACF ~ U(-1, 1)); ``"cells"`` (:mod:`.noise`,
log lam ~ N(-4, 3^2), rho ~ U(0, 0.99)). theta is integrated out: with H = G / s^2 + I / prior_scale^2,
m = H^-1 h / s^2, log p(y | s, eta) = -1/2 [n log(2 pi s^2) + log|V| + q/s^2 - m'h/s^2 + log|H| +
p log prior_scale^2]; NUTS samples (s, eta) and theta ~ N(m, H^-1) is drawn exactly.
Pointwise log-likelihood per cell (as :mod:`.compare`).
"""

from __future__ import annotations

from functools import lru_cache, partial
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from .cells import RateData
from .model import Orders, Scaling, raw_map, raw_offset, unpack
from .fit import _xy, default_scaling, parse_noise
from .noise import cell_stats
from ..inference.convergence import converged, ess_floor
from ..support.programs import program


class BayesFit(NamedTuple):
    """Posterior draws (scaled theta, (chains, draws, p)), diagnostics and ArviZ data."""

    theta: np.ndarray
    sigma: np.ndarray  # (chains, draws) white / innovation std, output units
    orders: Orders
    scaling: Scaling
    noise: str
    idata: object  # arviz.InferenceData with a per-cell log_likelihood group
    rhat_max: float
    ess_min: float
    divergences: int
    converged: bool

    def raw_draws(self) -> np.ndarray:
        """(chains, draws, p) draws of the raw (paper) coefficients."""
        return (self.theta @ raw_map(self.orders, self.scaling).T
                + raw_offset(self.orders, self.scaling))


# ------------------------------------------------------------------------- whitening
def _ar_whiten(phi, X, y, first, n):
    """Whitened (X~, y~) and log|V| of AR(p) noise within cells (unit innovations).

    Rows t >= p: x_t - sum phi_i x_{t-i}; the first p rows of every cell (``first``,
    (K, p)) are replaced by L_p^-1 x, Gamma_p = L_p L_p^T (their stationary covariance).
    """
    from ..models.arma import arma_acov

    p = phi.shape[0]
    g = arma_acov(phi, jnp.zeros(0), 1.0, p)
    idx = jnp.abs(jnp.arange(p)[:, None] - jnp.arange(p)[None, :])
    Lp = jnp.linalg.cholesky(g[idx])
    Linv = jax.scipy.linalg.solve_triangular(Lp, jnp.eye(p), lower=True)
    Z = jnp.concatenate([X, y[:, None]], axis=1)
    tail = Z[p:] - sum(phi[i] * Z[p - 1 - i:n - 1 - i] for i in range(p))
    Zw = jnp.concatenate([Z[:p], tail], axis=0)
    Zw = Zw.at[first].set(jnp.einsum("ij,kjc->kic", Linv, Z[first]))
    logdet = first.shape[0] * 2.0 * jnp.sum(jnp.log(jnp.diag(Lp)))
    return Zw[:, :-1], Zw[:, -1], logdet


def _tridiag_solve(diag, off, V):
    """B^-1 V and log|B| for a symmetric tridiagonal SPD B (LDL^T in two lax.scans)."""
    def fwd(carry, x):
        d_prev, z_prev = carry
        a, b, v = x
        lk = b / d_prev
        d = a - lk * b
        z = v - lk * z_prev
        return (d, z), (d, z, lk)

    b_lead = jnp.concatenate([jnp.zeros(1), off])
    init = (jnp.ones(()), jnp.zeros(V.shape[1:]))
    # not unrolled: inside NUTS (gradient, the Laplace Hessian, chains vmapped) unroll=16
    # compiled the paper000 posterior in ~165 s against ~38 s, and ran no faster
    _, (d, z, lk) = jax.lax.scan(fwd, init, (diag, b_lead, V))

    def bwd(x_next, x):
        dk, zk, l_next = x
        xk = zk / dk - l_next * x_next
        return xk, xk

    l_next = jnp.concatenate([lk[1:], jnp.zeros(1)])
    _, X = jax.lax.scan(bwd, jnp.zeros(V.shape[1:]), (d, z, l_next[:, None] * jnp.ones_like(z)),
                        reverse=True)
    return X, jnp.sum(jnp.log(d))


def _cells_suff(lam, rho, st):
    """(G, h, q, log|V|) of white + AR(1)-across-cells noise, O(K p) (:mod:`.noise`)."""
    r = rho ** st["gaps"]
    w = 1.0 / (1.0 - r * r)
    qd = jnp.ones(st["N"].shape[0]).at[:-1].add(r * r * w).at[1:].add(w - 1.0)
    qo = -r * w
    logdetR = jnp.sum(jnp.log1p(-r * r))
    Nc = st["N"][:, None]
    V = jnp.concatenate([st["Xb"], st["yb"][:, None]], axis=1)

    def Qv(v):
        return qd[:, None] * v + jnp.zeros_like(v).at[:-1].add(qo[:, None] * v[1:]).at[1:].add(
            qo[:, None] * v[:-1])

    NV, QV = Nc * V, Qv(V)
    both = jnp.concatenate([NV, QV], axis=1)
    sol, logdetB = _tridiag_solve(qd + lam * st["N"], qo, both)
    k = V.shape[1]
    white_side = NV - lam * Nc * sol[:, :k]  # Sigma^-1 V where lam n is small
    offset_side = (QV - Qv(sol[:, k:])) / lam  # ... and where it is large (no cancellation)
    A = jnp.where(lam * jnp.median(st["N"]) <= 1.0, white_side, offset_side)
    G = st["WXX"] + st["Xb"].T @ A[:, :-1]
    h = st["WXy"] + st["Xb"].T @ A[:, -1]
    q = st["Wyy"] + st["yb"] @ A[:, -1]
    logdet = logdetR + logdetB  # log|V/s2| = sum log n + log|Sigma| = log|R| + log|B|
    return G, h, q, logdet


def _suff(noise, eta, data):
    """Sufficient statistics of the whitened regression for the noise parameters eta."""
    if noise == "cells":
        return _cells_suff(jnp.exp(eta["log_lam"]), eta["rho"], data["st"])
    X, y = data["X"], data["y"]
    if noise == "white":
        return X.T @ X, X.T @ y, y @ y, 0.0
    from ..models.arma import pacf_to_ar

    Xw, yw, logdet = _ar_whiten(pacf_to_ar(eta["pacf"]), X, y, data["first"], y.shape[0])
    return Xw.T @ Xw, Xw.T @ yw, yw @ yw, logdet


def _conditional(G, h, s2, prior_scale):
    """Cholesky factor of H = G / s2 + I / prior_scale^2 and the mean m = H^-1 h / s2."""
    H = G / s2 + jnp.eye(G.shape[0]) / prior_scale ** 2
    cf = jnp.linalg.cholesky(H)
    m = jax.scipy.linalg.cho_solve((cf, True), h / s2)
    return cf, m


@partial(program, static_argnames=("noise", "prior_scale"))
def marginal_loglik(noise: str, eta: dict, data: dict, *, prior_scale: float):
    """log p(y | s, eta) with theta integrated out (module doc); jit/grad-able.

    Jitted so that NumPyro's eager initialisation trace compiles it once instead of
    dispatching (and compiling) every primitive separately.
    """
    G, h, q, logdetV = _suff(noise, eta, data)
    s2 = eta["sigma"] ** 2
    cf, m = _conditional(G, h, s2, prior_scale)
    n, p = data["y"].shape[0], G.shape[0]
    return -0.5 * (n * jnp.log(2 * jnp.pi * s2) + logdetV + (q - m @ h) / s2
                   + 2 * jnp.sum(jnp.log(jnp.diag(cf))) + p * jnp.log(prior_scale ** 2))


def _model(data, start, *, noise: str, p_ar: int, prior_scale: float):
    """sigma is sampled as sigma = s_hat exp(c u) with c = 1 / sqrt(2 n), the posterior sd of
    log sigma, so that every coordinate NUTS sees has a posterior scale of about 1 (else
    warm-up starts with a condition number ~1e4 and maximal trees). Its prior stays
    HalfNormal(1): the density enters as a factor with the Jacobian sigma c."""
    import numpyro
    import numpyro.distributions as dist
    from numpyro.distributions import constraints

    c = 1.0 / jnp.sqrt(2.0 * data["y"].shape[0])
    u = numpyro.sample("u_sigma", dist.ImproperUniform(constraints.real, (), ()))
    sigma = numpyro.deterministic("sigma", start["sigma"] * jnp.exp(c * u))
    numpyro.factor("sigma_prior", dist.HalfNormal(1.0).log_prob(sigma) + jnp.log(sigma * c))
    eta = {"sigma": sigma}
    if noise == "cells":
        eta["log_lam"] = numpyro.sample("log_lam", dist.Normal(-4.0, 3.0))
        eta["rho"] = numpyro.sample("rho", dist.Uniform(0.0, 0.99))
    elif p_ar:
        eta["pacf"] = numpyro.sample("pacf", dist.Uniform(-1.0, 1.0).expand([p_ar]).to_event(1))
    numpyro.factor("marginal_loglik", marginal_loglik(noise, eta, data, prior_scale=prior_scale))


def _start(data: RateData, orders: Orders, sc: Scaling, noise: str, p_ar: int) -> dict:
    """Least-squares values of the noise parameters: sigma's centring and NUTS's start."""
    from .fit import fit_joint

    ls = fit_joint(data, orders, scaling=sc, noise=noise)
    start = {"sigma": ls.sigma / sc.U_scale}
    init = {"u_sigma": 0.0}
    if noise == "cells":
        init["log_lam"] = float(np.clip(np.log(max(ls.lam, 1e-12)), -12.0, 6.0))
        init["rho"] = float(np.clip(ls.rho, 0.05, 0.95))
    elif p_ar:
        from ..models.arma import ar_to_pacf

        init["pacf"] = np.clip(np.asarray(ar_to_pacf(jnp.asarray(ls.ar))), -0.95, 0.95)
    return start, init


def _pointwise(noise, eta, theta, data, K):
    """Per-cell log-likelihood at one draw (for WAIC/LOO)."""
    s2 = eta["sigma"] ** 2
    cell = data["cell"]
    if noise == "cells":  # each cell's mean given the other cells' (:mod:`.compare`)
        st = data["st"]
        lam = jnp.exp(eta["log_lam"])
        rb = st["yb"] - st["Xb"] @ theta
        wc = st["Wyy_c"] - 2 * st["WXy_c"] @ theta + jnp.einsum("kij,i,j->k", st["WXX_c"],
                                                                theta, theta)
        pos = jnp.concatenate([jnp.zeros(1), jnp.cumsum(st["gaps"])])
        R = eta["rho"] ** jnp.abs(pos[:, None] - pos[None, :])
        Q = jnp.linalg.inv(jnp.diag(1.0 / st["N"]) + lam * R) / s2
        g, q = Q @ rb, jnp.diag(Q)
        return (-0.5 * ((st["N"] - 1) * jnp.log(2 * jnp.pi * s2) + wc / s2)
                - 0.5 * jnp.log(st["N"]) - 0.5 * jnp.log(2 * jnp.pi / q) - 0.5 * g * g / q)
    X, y = data["X"], data["y"]
    logdet_cell = 0.0
    if noise != "white":
        from ..models.arma import pacf_to_ar

        X, y, logdet = _ar_whiten(pacf_to_ar(eta["pacf"]), X, y, data["first"], y.shape[0])
        logdet_cell = logdet / K
    r = y - X @ theta
    point = jax.ops.segment_sum(-0.5 * (r * r / s2 + jnp.log(2 * jnp.pi * s2)), cell, K)
    return point - 0.5 * logdet_cell


def cell_data(X, y, cell, t_abs, K, p_ar):
    """Everything the model needs, as jnp arrays (per-cell arrays in cell_stats' time order)."""
    st = cell_stats(X, y, cell, t_abs)
    N = np.bincount(cell, minlength=K).astype(float)
    order = np.argsort(np.bincount(cell, t_abs, K) / N, kind="stable")
    Xb = np.stack([np.bincount(cell, X[:, j], K) for j in range(X.shape[1])], 1) / N[:, None]
    Xc, yc = X - Xb[cell], y - (np.bincount(cell, y, K) / N)[cell]
    WXX_c = np.zeros((K, X.shape[1], X.shape[1]))
    np.add.at(WXX_c, cell, Xc[:, :, None] * Xc[:, None, :])
    WXy_c = np.zeros((K, X.shape[1]))
    np.add.at(WXy_c, cell, Xc * yc[:, None])
    sd = dict(st._asdict(), WXX_c=WXX_c[order], WXy_c=WXy_c[order],
              Wyy_c=np.bincount(cell, yc * yc, K)[order])
    sd.pop("n")
    q = max(p_ar, 1)
    first = np.stack([np.flatnonzero(cell == k)[:q] for k in range(K)])
    return {"X": jnp.asarray(X), "y": jnp.asarray(y), "cell": jnp.asarray(cell),
            "first": jnp.asarray(first), "st": {k: jnp.asarray(v) for k, v in sd.items()}}


@lru_cache(maxsize=8)
def _sampler(noise: str, p_ar: int, prior_scale: float, target_accept: float, warmup: int,
             samples: int, chain_method: str):
    """Warm-up + sampling of NUTS chains as one jitted function, compiled once per
    configuration and data shape (NumPyro's functional ``hmc`` API; the data are arguments,
    so another table of the same shape reuses it: a new ``MCMC`` object per call compiled
    again for ~15 s). Returns constrained draws (chains, samples, ...) and divergences."""
    from numpyro.infer.util import constrain_fn, potential_energy

    from ..inference.nuts import chain_sampler

    model = partial(_model, noise=noise, p_ar=p_ar, prior_scale=prior_scale)
    return chain_sampler(
        lambda d, start: partial(potential_energy, model, (d, start), {}), warmup, samples,
        target_accept_prob=target_accept, dense_mass=False, chain_method=chain_method,
        postprocess=lambda z, d, start: constrain_fn(model, (d, start), {}, z,
                                                     return_deterministic=True),
        store_key=("composite.bayes", noise, p_ar, prior_scale) if chain_method == "threads"
        else None)


def _unconstrained(init: dict, chains: int) -> dict:
    """Start values (the GLS fit's) in NUTS's unconstrained space, one row per chain."""
    from numpyro.distributions import constraints
    from numpyro.distributions.transforms import biject_to

    support = {"u_sigma": constraints.real, "log_lam": constraints.real,
               "rho": constraints.interval(0.0, 0.99), "pacf": constraints.interval(-1.0, 1.0)}
    out = {}
    for k, v in init.items():
        u = biject_to(support[k]).inv(jnp.asarray(v, dtype=float))
        out[k] = jnp.broadcast_to(u, (chains,) + jnp.shape(u))
    return out


@partial(program, static_argnames=("noise", "prior_scale", "K"))
def _draw_theta(flat: dict, keys, d: dict, *, noise: str, prior_scale: float, K: int):
    """theta | (s, eta), y drawn exactly for every posterior draw, and its per-cell
    log-likelihood. The data go in as an argument, not a closure: closed-over arrays become
    XLA constants, whose folding made this compile take tens of seconds."""
    def one(eta, key):
        G, h, _, _ = _suff(noise, eta, d)
        cf, m = _conditional(G, h, eta["sigma"] ** 2, prior_scale)
        z = jax.random.normal(key, m.shape)
        theta = m + jax.scipy.linalg.solve_triangular(cf.T, z, lower=False)
        return theta, _pointwise(noise, eta, theta, d, K)

    return jax.vmap(one)(flat, keys)


def fit_bayes(data: RateData, orders: Orders, *, seed: int, noise: str = "cells",
              scaling: Scaling | None = None, prior_scale: float = 10.0, chains: int = 4,
              warmup: int = 500, samples: int = 500, target_accept: float = 0.85,
              chain_method: str = "threads") -> BayesFit:
    """NUTS posterior of the full-matrix composite model (module doc).

    ``chain_method``: "threads" (default: each chain its own program, both cores busy),
    "sequential" or "vectorized" (:func:`fogbayes.inference.nuts.chain_sampler`).
    Convergence (reported, never hidden): R-hat < 1.01 and bulk ESS >= 100 per chain for
    every noise parameter (theta is drawn exactly given them), and no divergent transition;
    ``converged`` is False otherwise.
    """
    import arviz as az

    from ..errors import FogbayesError, TooShortError

    if chain_method not in ("vectorized", "sequential", "threads"):
        raise FogbayesError(f"unknown chain_method {chain_method!r}", column="chain_method",
                            fix="use 'threads' (one chain's program, chains side by side), "
                            "'sequential' (its draws, one after another) or 'vectorized'")
    sc = scaling or default_scaling(data)
    X, y = _xy(data, orders, sc)
    K = int(data.cell.max()) + 1
    p_ar = 0 if noise == "cells" else parse_noise(noise)
    counts = np.bincount(data.cell, minlength=K)
    if counts.min() <= max(p_ar, 1):
        raise TooShortError(f"a cell has {counts.min()} samples, too few for AR({p_ar}) noise",
                            column="input_rate", fix="hold every rate longer or lower the AR order")
    d = cell_data(X, y, data.cell, np.asarray(data.time, float), K, p_ar)
    start, init = _start(data, orders, sc, noise, p_ar)
    run = _sampler(noise, p_ar, float(prior_scale), float(target_accept), int(warmup),
                   int(samples), chain_method)
    keys = jax.random.split(jax.random.PRNGKey(seed), chains)
    draws, diverging = run(keys, _unconstrained(init, chains), d,
                           {k: jnp.asarray(v) for k, v in start.items()})
    post = {k: np.asarray(v) for k, v in draws.items() if k != "u_sigma"}
    div = int(np.sum(np.asarray(diverging)))

    flat = {k: jnp.asarray(v.reshape((-1,) + v.shape[2:])) for k, v in post.items()}
    keys = jax.random.split(jax.random.PRNGKey(seed + 1), flat["sigma"].shape[0])
    theta, point = _draw_theta(flat, keys, d, noise=noise, prior_scale=float(prior_scale), K=K)
    theta = np.asarray(theta).reshape(chains, samples, -1)
    point = np.asarray(point).reshape(chains, samples, K)
    idata = az.from_dict(posterior={**post, "theta": theta}, log_likelihood={"cells": point})
    # unrounded: az.summary rounds to 2 decimals by default, and a rounded 1.01 would fail
    # the strict R-hat < 1.01 test for any value in [1.005, 1.01)
    summ = az.summary(idata, var_names=list(post), kind="diagnostics", round_to="none")
    rhat, ess = float(np.nanmax(summ["r_hat"])), float(np.nanmin(summ["ess_bulk"]))
    ok = converged(rhat, ess, div, floor=ess_floor(chains))
    return BayesFit(theta, post["sigma"] * sc.U_scale, orders, sc, noise, idata, rhat, ess,
                    div, ok)


def posterior_params(fit: BayesFit, *, max_draws: int = 200):
    """Thinned draws as FullParams with a leading draw axis, and the noise std per draw
    (scaled output units), for :func:`fogbayes.composite.compensate.compensate_draws`."""
    th = fit.theta.reshape(-1, fit.theta.shape[-1])
    step = max(1, th.shape[0] // max_draws)
    return (unpack(jnp.asarray(th[::step]), fit.orders),
            fit.sigma.reshape(-1)[::step] / fit.scaling.U_scale)
