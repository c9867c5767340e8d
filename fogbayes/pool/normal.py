"""Hierarchical normal model of per-unit estimates: population, spread, shrunk units, outliers.

y_u | theta_u ~ N(theta_u, Sigma_u), theta_u ~ N(mu, diag s^2), mu_p ~ N(median y_p, 10^2),
s_p ~ HalfNormal(1); or e^{mu_p} ~ HalfCauchy(0, A_p) (:func:`amplitude_log_prior`), or a datasheet
``mu_prior``. Units integrate out, y_u ~ N(mu, S + Sigma_u); NUTS samples (eta, log s), mu
whitened given s (:func:`_mu_of`); shrunk
theta_u ~ N(mu + S(S + Sigma_u)^-1 (y_u - mu), S - S(S + Sigma_u)^-1 S); a new unit N(mu, S).
Outliers, leave-one-out (vmapped): p_u = E[P(chi2_P > (y_u - mu)'(S + Sigma_u)^-1 (y_u - mu))], or
per component (``outlier_test="each"``), Bonferroni. Censored components: likelihood
exp(-x'(4 Sigma_cc)^-1 x / 2), x_t = e^{2(theta_t - y_ut)} - 1 (:func:`unit_log_lik`,
:func:`censored_log_lik`), sampled non-centred; the leave-one-out table integrates them out
by quadrature (:func:`censored_marginal`), its ratios 1/p(y_u | mu, s).
"""

from __future__ import annotations

from ..inference.convergence import converged
import functools
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from ..support.tails import chi2_sf, norm_cdf, norm_sf
from ..support.programs import program

MU_PRIOR_SD = 10.0
SPREAD_PRIOR_SD = 1.0
#: convergence rule shared with the single-record posteriors (allan/bayes.py)
R_HAT_MAX, ESS_MIN = 1.01, 200.0


class PoolResult(NamedTuple):
    """Posterior of the population and of each unit (log-space parameters)."""

    names: tuple            # the P parameter names
    mu: np.ndarray          # (draws, P) population mean (log space)
    spread: np.ndarray      # (draws, P) between-unit sd s (log space)
    units: np.ndarray       # (draws, U, P) shrunk per-unit parameters
    new_unit: np.ndarray    # (draws, P) a new unit of the population
    outlier_p: np.ndarray   # (U,) leave-one-out posterior-predictive p-values
    diagnostics: dict       # r_hat, ess, divergences, converged
    adaptation: tuple = None  # the chains' mean inverse mass and step size (``start``)


#: the variance coefficient is exp(LINEAR_POWER * theta): Allan terms enter the AVAR squared
LINEAR_POWER = 2.0
#: exponent cap of the censored likelihood: beyond it the likelihood is below exp(-1e3)
_MAX_EXPONENT = 60.0
#: least share of the ceiling left to the other terms (v_hat <= (1 - this) S): a smaller
#: share makes a sharp knee in the likelihood where the sampler diverged (1 in 4000 draws, 4 of
#: 20 pools of four 1 h units at 1e-3); it caps the level's fall at log(0.05)^2 / var
_MIN_REST = 0.05


def censored_shift(theta, y, ceiling):
    """x = log((v - v_hat + S) / S) of a censored component, v = exp(2 theta),
    v_hat = exp(2 y), S = exp(2 ceiling) >= v_hat / (1 - _MIN_REST) (module docstring)."""
    a = jnp.minimum(LINEAR_POWER * (theta - ceiling), _MAX_EXPONENT)
    b = LINEAR_POWER * (y - ceiling)
    log_rest = jnp.log1p(-jnp.exp(b))  # log(1 - v_hat / S): the other terms' share
    return jnp.logaddexp(a, log_rest) - jnp.logaddexp(b, log_rest)


def censored_log_lik(theta, y, var, ceiling):
    """log L(theta) of one censored component: -x^2 / (2 var), x = :func:`censored_shift`;
    0 at y, level -log(1 - v_hat / S)^2 / (2 var) as theta -> -inf, log-quadratic above."""
    return -censored_shift(theta, y, ceiling) ** 2 / (2.0 * var)


def _resolved_log_lik(yu, cu, cens, mu, s):
    """log N(y_r; mu_r, Sigma_rr + S_rr) of a unit's resolved components (r = 1 - cens)."""
    r = 1.0 - cens
    A = (cu + jnp.diag(s**2)) * jnp.outer(r, r) + jnp.diag(cens)
    L = jnp.linalg.cholesky(A)
    z = jax.scipy.linalg.solve_triangular(L, (yu - mu) * r, lower=True)
    return (-0.5 * z @ z - jnp.sum(jnp.log(jnp.diag(L)))
            - 0.5 * jnp.sum(r) * jnp.log(2 * jnp.pi))


def unit_log_lik(yu, cu, cens, mu, s, theta, ceil):
    """log p(y_u | mu, s, theta_u): the unit's resolved components integrated out,
    N(y_r; mu_r, Sigma_rr + S_rr), times its censored components' joint likelihood at their
    sampled parameters ``theta``: normal in x = :func:`censored_shift` with covariance
    Sigma_cc (``cu``'s censored block; ``ceil`` the ceilings; no covariance between the
    censored and the resolved components; ``theta`` of resolved components is ignored)."""
    r = 1.0 - cens
    gauss = _resolved_log_lik(yu, cu, cens, mu, s)
    Lc = jnp.linalg.cholesky(cu * jnp.outer(cens, cens) + jnp.diag(r))
    x = jnp.where(cens > 0, censored_shift(theta, yu, jnp.where(cens > 0, ceil, yu + 1.0)), 0.0)
    zc = jax.scipy.linalg.solve_triangular(Lc, x, lower=True)
    return gauss - 0.5 * zc @ zc


def _shift_np(theta, y, ceiling):
    """:func:`censored_shift` in NumPy (the grids are built outside the sampler)."""
    a = np.minimum(LINEAR_POWER * (theta - ceiling), _MAX_EXPONENT)
    b = LINEAR_POWER * (y - ceiling)
    log_rest = np.log1p(-np.exp(b))
    return np.logaddexp(a, log_rest) - np.logaddexp(b, log_rest)


#: nodes of a censored component's quadrature grid (:func:`censored_grids`) by the most
#: components one unit censors, (plateau, core, tail): the tensor grid of a unit has M^D
#: points, M their sum. The error of its marginal against a fine grid:
#: tests/test_pool.py (test_censored_marginal_matches_a_fine_grid)
GRID_NODES = {1: (24, 92, 5), 2: (24, 92, 5), 3: (8, 28, 4)}
#: a component's core spans x in [max(x(-inf), -X_SPAN sd), X_SPAN sd], its tail nodes go on
#: to (X_SPAN + X_TAIL) sd, where the likelihood is below exp(-60); beyond the grid the
#: likelihood is held at its last node's value
X_SPAN, X_TAIL = 6.0, 5.0
#: singular values of a unit's two-component likelihood grid below this share of the largest
#: are dropped: the grid's likelihood is then sum_r a_r(theta_1) b_r(theta_2) to ~1e-10
LOW_RANK_TOL = 1e-10
#: the terms kept (the 1 h units' grids need 11-14 to LOW_RANK_TOL, at most M)
LOW_RANK = 20


def _component_nodes(y, c, var, counts):
    """Increasing nodes theta of one censored component's grid (``counts``: plateau, core,
    tail): uniform in the shift x (:func:`censored_shift`, in which the likelihood is normal,
    variance ``var``) over the core [max(x(-inf), -X_SPAN sd), X_SPAN sd], mapped to
    theta = c + log(e^x - e^x(-inf)) / 2, then ``tail`` coarser nodes above it (and below
    it where the plateau x(-inf) lies beyond the core). Where the plateau lies inside, the
    plateau nodes approach it geometrically, x - x(-inf) from the core's spacing h down to
    1e-9 var / |x(-inf)|, where the likelihood is level to ~1e-9 (it is held at the lowest
    node's value below)."""
    Mp, Mx, Mt = counts
    sd = np.sqrt(var)
    log_rest = np.log1p(-np.exp(LINEAR_POWER * (y - c)))
    hi = X_SPAN * sd
    tail = hi + np.linspace(0.0, X_TAIL * sd, Mt + 1)[1:]
    if log_rest > -hi:
        core = np.linspace(log_rest, hi, Mx + 1)[1:]
        h = core[1] - core[0]
        eps = min(1e-9 * var / max(abs(log_rest), sd), 0.5 * h)
        x = np.concatenate([log_rest + h * (eps / h) ** (np.arange(Mp, 0, -1) / Mp), core, tail])
    else:
        low = -hi - np.linspace(0.0, X_TAIL * sd, Mt + 1)[:0:-1]
        low = np.maximum(low, log_rest + 1e-3 * sd)
        x = np.concatenate([low, np.linspace(-hi, hi, Mp + Mx), tail])
    # e^x - e^log_rest = rest (e^(x - log_rest) - 1): precise near the plateau
    return c + (log_rest + np.log(np.expm1(x - log_rest))) / LINEAR_POWER


def censored_grids(y, cov, cens, ceil):
    """Each unit's quadrature grid of its censored components (:func:`censored_marginal`):
    ``slots`` (U, D) the components (padding: component 0, the likelihood constant along it),
    ``nodes`` (U, D, M) increasing parameters theta and ``lik`` (U, M, ..., M) the
    censored likelihood exp(-x' Sigma_cc^-1 x / 2) at the tensor grid's points, D the most
    components a unit censors (0: none).

    Per component the nodes are :func:`_component_nodes`; with two components the grid's
    likelihood is kept as its truncated SVD, ``lik`` (U, 2, M, R) the factors
    (:data:`LOW_RANK_TOL`), and with one as (U, 1, M, 1)."""
    y, cov, cens, ceil = (np.asarray(a, dtype=float) for a in (y, cov, cens, ceil))
    U, P = y.shape
    counts = cens.sum(axis=1).astype(int)
    D = int(counts.max()) if U else 0
    if D == 0:
        return np.zeros((U, 0), int), np.zeros((U, 0, 1)), np.ones((U,))
    # one or two components: one shape of the grids (two slots), one compiled table per (U, P)
    D = max(D, min(2, P))
    counts = GRID_NODES.get(D, GRID_NODES[3])
    M = sum(counts)
    slots = np.zeros((U, D), int)
    nodes = np.tile(np.linspace(-1.0, 1.0, M), (U, D, 1))
    lik = np.ones((U,) + (M,) * D)
    for u in range(U):
        c = np.flatnonzero(cens[u] > 0)
        if not c.size:
            continue
        slots[u, :c.size] = c
        xs = []
        for d, t in enumerate(c):
            th = _component_nodes(y[u, t], ceil[u, t], cov[u, t, t], counts)
            nodes[u, d] = th
            xs.append(_shift_np(th, y[u, t], ceil[u, t]))
        inv = np.linalg.inv(cov[u][np.ix_(c, c)])
        grid = np.meshgrid(*xs, indexing="ij")
        q = sum(inv[i, j] * grid[i] * grid[j] for i in range(c.size) for j in range(c.size))
        lu = np.exp(np.maximum(-0.5 * q, -700.0))
        lik[u] = lu.reshape(lu.shape + (1,) * (D - c.size))  # constant along padded slots
    if D == 2:  # the likelihood's tensor as a sum of separable terms (its SVD, truncated)
        uu, sv, vv = np.linalg.svd(lik)
        R = LOW_RANK  # a fixed rank: one shape of the grids; the terms past the tolerance 0
        sv = np.where(sv > LOW_RANK_TOL * sv[:, :1], sv, 0.0)
        root = np.sqrt(sv[:, :R])
        lik = np.stack([uu[:, :, :R] * root[:, None, :],
                        np.swapaxes(vv[:, :R, :], 1, 2) * root[:, None, :]], axis=1)
    elif D == 1:
        lik = lik[:, None, :, None]
    return slots, nodes, lik


def _bins(nodes, mu, s):
    """The bins of a component's grid under theta ~ N(mu, s^2): the mass below the first
    node, of each bin between nodes and above the last (M + 1,), and of each bin
    E[(theta - t_k) / h_k 1(t_k < theta < t_k+1)] (M - 1,), in closed form (Phi, phi) and
    in the tail that keeps precision far above mu."""
    from jax.scipy.special import ndtr

    a = (nodes - mu) / s
    q = ndtr(-jnp.abs(a))  # the smaller tail at each node: one ndtr a node, full precision
    below = jnp.where(a < 0, q, 1.0 - q)  # Phi(a)
    lo = below[0]
    hi = jnp.where(a[-1] > 0, q[-1], 1.0 - q[-1])
    # a bin above mu: q_k - q_k+1; below: q_k+1 - q_k; across: 1 - q_k - q_k+1
    mass = jnp.where(a[:-1] >= 0, q[:-1] - q[1:],
                     jnp.where(a[1:] <= 0, q[1:] - q[:-1], 1.0 - q[:-1] - q[1:]))
    pdf = jnp.exp(-0.5 * a**2) / jnp.sqrt(2.0 * jnp.pi)
    h = nodes[1:] - nodes[:-1]
    ramp = s * (pdf[:-1] - pdf[1:] - a[:-1] * mass) / h
    return lo, mass, hi, ramp


def hat_weights(nodes, mu, s):
    """w_k = E[hat_k(theta)], theta ~ N(mu, s^2): the expectations of the piecewise-linear
    interpolant's basis on ``nodes`` (the first and last held constant beyond the grid),
    so that sum_k w_k f(t_k) is E[f(theta)] of the interpolant of f exactly, for any s
    (s -> 0 gives the interpolant at mu); the weights sum to 1."""
    lo, mass, hi, ramp = _bins(nodes, mu, s)
    left = mass - ramp
    w = jnp.concatenate([jnp.atleast_1d(lo), jnp.zeros_like(mass)]) + jnp.concatenate(
        [left, jnp.zeros(1)]) + jnp.concatenate([jnp.zeros(1), ramp]) + jnp.concatenate(
        [jnp.zeros_like(mass), jnp.atleast_1d(hi)])
    return w


def censored_marginal(mu, s, slots, nodes, lik):
    """log E[exp(-x' Sigma_cc^-1 x / 2)] of one unit over its censored components
    theta_t ~ N(mu_t, s_t^2), independent given (mu, s): the tensor product of each
    component's :func:`hat_weights` contracted with its grid's likelihood
    (:func:`censored_grids`). The likelihood lies in [e^-700, 1] and the weights sum to 1,
    so the sum is neither over- nor underflowed; differentiable in (mu, s)."""
    D = slots.shape[0]
    if D == 0:
        return jnp.zeros(())
    if D <= 2:  # factors (D, M, R): sum_r prod_d (w_d' F_d)_r
        t = jnp.ones(lik.shape[-1])
        for d in range(D):
            t = t * (hat_weights(nodes[d], mu[slots[d]], s[slots[d]]) @ lik[d])
        return jnp.log(jnp.maximum(jnp.sum(t), 1e-300))
    t = lik
    for d in range(D - 1, -1, -1):
        t = t @ hat_weights(nodes[d], mu[slots[d]], s[slots[d]])
    return jnp.log(jnp.maximum(t, 1e-300))


def unit_marginal(yu, cu, cens, mu, s, slots, nodes, lik):
    """log p(y_u | mu, s): the resolved components' N(y_r; mu_r, Sigma_rr + S_rr) times the
    censored components' likelihood integrated over theta_c ~ N(mu_c, S_cc)
    (:func:`censored_marginal`; :func:`unit_log_lik` at the parameters integrated)."""
    gauss = _resolved_log_lik(yu, cu, cens, mu, s)
    return gauss + censored_marginal(mu, s, slots, nodes, lik)


def _log_marginal(y, cov, cens, ceil, w, mu, s, theta):
    """sum_u w_u log p(y_u | mu, s, theta_u)."""
    return jnp.sum(w * jax.vmap(unit_log_lik, in_axes=(0, 0, 0, None, None, 0, 0))(
        y, cov, cens, mu, s, theta, ceil))


def amplitude_log_prior(mu, log_scale):
    """log density of mu = log m under m ~ HalfCauchy(0, A), log A = ``log_scale``:
    log(2 / pi) + (mu - log A) - log(1 + (m / A)^2) (the Jacobian dm/dmu = m included)."""
    x = mu - log_scale
    return jnp.log(2.0 / jnp.pi) + x - jnp.logaddexp(0.0, 2.0 * x)


#: the sd (log units) standing in for a component's prior in the centre and scale of
#: :func:`_mu_of` where few units resolve it; any value gives the same posterior
_ETA_PRIOR_SD = 1.0


def _mu_of(eta, log_s, y, cov, cens, w, centre):
    r"""mu = m(s) + d(s) eta, and log prod d(s): the population mean given the spreads,
    whitened (the sampled parameter is eta, not mu).

    Given s, the resolved units put mu_p about their weighted mean
    m_p = (sum_u w_up y_up + c_p / a^2) / (sum_u w_up + 1 / a^2), w_up = 1 / (s_p^2 +
    Sigma_u,pp), with sd d_p = (sum_u w_up + 1 / a^2)^{-1/2} (a = _ETA_PRIOR_SD, c the
    start's centre). As s -> 0 that sd shrinks to the units' own errors (1 % for N at 1 h)
    while at s ~ 0.1 it is ten times wider: a funnel in (mu, log s) that NUTS crossed
    slowly (R-hat 1.065, ESS 67 for mu_N on the four 1 h units of benchmarks/RESULTS_pool.md
    at target acceptance 0.995). In (eta, log s) the funnel is gone. The map is a bijection
    for each s, triangular in (eta, log s), so the density takes the factor prod_p d_p."""
    r = (1.0 - cens) * w[:, None]
    wt = r / (jnp.exp(2.0 * log_s)[None, :] + jnp.diagonal(cov, axis1=1, axis2=2))
    prec = jnp.sum(wt, axis=0) + 1.0 / _ETA_PRIOR_SD**2
    m = (jnp.sum(wt * y, axis=0) + centre / _ETA_PRIOR_SD**2) / prec
    return m + eta / jnp.sqrt(prec), -0.5 * jnp.sum(jnp.log(prec))


def _constrained(z, y, cov, cens, ceil, w, centre, mu_sd, log_scale):
    """The sampler's draw z = (eta, log s, z) as (mu, log s, z) (:func:`_mu_of`)."""
    mu, _ = _mu_of(z["eta"], z["log_s"], y, cov, cens, w, centre)
    return {"mu": mu, "log_s": z["log_s"], "z": z["z"]}


def _potential(y, cov, cens, ceil, w, centre, mu_sd, log_scale):
    from jax.scipy.stats import norm

    amplitude = jnp.isfinite(log_scale)
    log_scale = jnp.where(amplitude, log_scale, 0.0)  # no NaN in the branch not taken

    def potential(z):
        log_s = z["log_s"]
        mu, log_jac = _mu_of(z["eta"], log_s, y, cov, cens, w, centre)
        s = jnp.exp(log_s)
        lp = jnp.sum(jnp.where(amplitude, amplitude_log_prior(mu, log_scale),
                               norm.logpdf(mu, centre, mu_sd)))
        # HalfNormal(1) on s, sampled as log s (+ the Jacobian log s)
        lp += jnp.sum(norm.logpdf(s, 0.0, SPREAD_PRIOR_SD) + jnp.log(2.0) + log_s)
        # censored components, non-centred: theta = mu + s z, z ~ N(0, 1) (z of the resolved
        # components is a free standard normal the likelihood does not see)
        lp += jnp.sum(norm.logpdf(z["z"]))
        theta = mu + s * z["z"]
        return -(lp + log_jac + _log_marginal(y, cov, cens, ceil, w, mu, s, theta))

    return potential


#: NUTS target acceptance and default warm-up: resolved components only, and with censored
#: components sampled (their likelihood is level below and steep near the estimate: at 0.98
#: and 500 warm-up the four 1 h units of benchmarks/RESULTS_pool.md gave R-hat 1.011 or a
#: divergence; at 0.995 and 1000 neither, on sampler seeds 0, 2 and 3)
TARGET_ACCEPT, TARGET_ACCEPT_CENSORED, WARMUP, WARMUP_CENSORED = 0.98, 0.995, 500, 1000


#: XLA compiles the pool's chains without LLVM's optimisations: a small potential whose
#: time goes to the tree builder's control flow, not arithmetic. `fogbayes pool` on the four
#: 1 h units of benchmarks/RESULTS_interactive.md, alternating warm calls: 10.6-12.9 s against
#: 16.4-18.5 s. The Allan posterior, arithmetic-bound, ran 2.6x slower so: it keeps the default.
COMPILER_OPTIONS = {"xla_backend_optimization_level": 0}


#: warm-up steps of a posterior started from a related one's adaptation (``start`` of
#: :func:`fit_pool`): its mass matrix and step size are kept, these steps only carry the
#: chains into the posterior. The sampled parameters are whitened (:func:`_mu_of`,
#: non-centred z), so the same units with covariances moved to the population median
#: leave the adaptation right
START_WARMUP = 150


@functools.lru_cache(maxsize=8)
def _sampler(num_warmup: int, num_samples: int, target: float = TARGET_ACCEPT,
             warm_start: bool = False):
    """NUTS chains over (eta, log s, z), drawn as (mu, log s, z) (:func:`_constrained`,
    :mod:`fogbayes.inference.nuts`), with each chain's adapted mass and step size; the unit
    weights are an argument, so the full fit and every leave-one-out refit share one
    compilation per (U, P). ``warm_start``: the first argument is an adaptation to keep
    (:data:`START_WARMUP`). The chains run in threads, one per core (vmapped, every chain
    waited at each step for the deepest tree of the four); the draws are those of chains
    run one after another."""
    from ..inference.nuts import chain_sampler

    return chain_sampler(_potential, num_warmup, num_samples, target_accept_prob=target,
                         chain_method="threads", postprocess=_constrained,
                         store_key=("pool.normal",), compiler_options=COMPILER_OPTIONS,
                         warm_start=warm_start, adapt_step_size=not warm_start,
                         return_adaptation=True)


def _start(y, cov, num_chains, rng):
    """Chains start near the precision-weighted mean (eta about 0, :func:`_mu_of`) and the
    spread of the estimates."""
    centre = np.median(y, axis=0)
    spread = np.maximum(np.std(y, axis=0), 0.05)
    eta0 = 0.1 * rng.standard_normal((num_chains, y.shape[1]))
    ls0 = np.log(spread) + 0.1 * rng.standard_normal((num_chains, y.shape[1]))
    z0 = 0.1 * rng.standard_normal((num_chains,) + y.shape)
    return centre, {"eta": jnp.asarray(eta0), "log_s": jnp.asarray(ls0), "z": jnp.asarray(z0)}


def _summary(zs, div) -> dict:
    from numpyro.diagnostics import summary

    diag = summary({"mu": zs["mu"], "log_s": zs["log_s"]}, group_by_chain=True)
    r_hat = max(float(np.max(diag[k]["r_hat"])) for k in ("mu", "log_s"))
    ess = min(float(np.min(diag[k]["n_eff"])) for k in ("mu", "log_s"))
    divergences = int(np.asarray(div).sum())
    return {"r_hat_max": r_hat, "ess_min": ess, "divergences": divergences,
            "converged": converged(r_hat, ess, divergences, floor=ESS_MIN)}


def shrink(y, cov, mu, spread, rng, cens=None, theta=None) -> np.ndarray:
    """Draws of each unit's parameters given population draws (see the module docstring).

    ``y`` (U, P), ``cov`` (U, P, P), ``mu``/``spread`` (D, P) -> (D, U, P). A censored
    component (``cens``) is independent of the resolved ones and is not normal given
    (mu, S): its draws are ``theta`` (D, U, P), the sampler's draws of it (required when
    any component is censored)."""
    U, P = y.shape
    cens = np.zeros((U, P)) if cens is None else np.asarray(cens, dtype=float)
    if cens.any() and theta is None:
        raise ValueError("censored components are drawn by the sampler: pass its theta")
    r = 1.0 - cens
    cov_r = cov * r[:, :, None] * r[:, None, :] + np.eye(P) * (cens * 1e30)[:, None, :]
    S = spread[:, None, :, None] * np.eye(P) * spread[:, None, None, :]  # (D,1,P,P)
    A = S + cov_r[None]                                                        # (D,U,P,P)
    gain = np.swapaxes(np.linalg.solve(A, np.broadcast_to(S, A.shape)), -1, -2)  # S A^-1
    mean = mu[:, None, :] + np.einsum("duij,duj->dui", gain, (y * r)[None] - (mu[:, None, :] * r))
    var = S - gain @ S
    var = 0.5 * (var + np.swapaxes(var, -1, -2)) + 1e-15 * np.eye(P)
    L = np.linalg.cholesky(var)
    out = mean + np.einsum("duij,duj->dui", L, rng.standard_normal(mean.shape))
    return np.where(cens[None] > 0, theta if theta is not None else out, out)


def _run(y, cov, cens, ceil, w, centre, mu_sd, log_scale, z0, key, num_warmup, num_samples,
         num_chains, start=None):
    """One posterior of (mu, s) with unit weights ``w``: draws (D, P) twice, diagnostics,
    the draws (D, U, P) of the units' parameters (meaningful for censored components) and
    the chains' adaptation (mean inverse mass, geometric-mean step size). ``start``: an
    adaptation to keep (:data:`START_WARMUP`)."""
    keys = jax.random.split(key, num_chains)
    target = TARGET_ACCEPT_CENSORED if np.any(cens) else TARGET_ACCEPT
    if num_warmup is None:
        num_warmup = WARMUP_CENSORED if np.any(cens) else WARMUP
    lead = ()
    if start is not None:
        num_warmup = START_WARMUP
        lead = ((jnp.asarray(start[0]), jnp.asarray(start[1])),)
    zs, div, (inverse_mass, step_size) = _sampler(num_warmup, num_samples, target,
                                                  start is not None)(
        keys, z0, *lead, jnp.asarray(y), jnp.asarray(cov), jnp.asarray(cens),
        jnp.asarray(ceil), jnp.asarray(w), jnp.asarray(centre), jnp.asarray(mu_sd),
        jnp.asarray(log_scale))
    zs = {k: np.asarray(v) for k, v in zs.items()}
    U, P = y.shape
    mu, spread = zs["mu"].reshape(-1, P), np.exp(zs["log_s"]).reshape(-1, P)
    theta = mu[:, None, :] + spread[:, None, :] * zs["z"].reshape(-1, U, P)
    adaptation = (np.asarray(inverse_mass).mean(axis=0),
                  float(np.exp(np.mean(np.log(np.asarray(step_size))))))
    return mu, spread, _summary(zs, div), theta, adaptation


def _start_without(adaptation, u: int, P: int) -> tuple:
    """The pool's adaptation for its refit without unit ``u``: the unit's z (raveled after
    eta and log s, NumPyro's key order) no longer meet its data and are standard normal,
    so their rows and columns of the inverse mass become the identity's."""
    inverse_mass, step_size = adaptation
    inverse_mass = np.array(inverse_mass)
    idx = 2 * P + u * P + np.arange(P)
    inverse_mass[idx, :] = inverse_mass[:, idx] = 0.0
    inverse_mass[idx, idx] = 1.0
    return inverse_mass, step_size


def _log_lik_table(y, cov, cens, grid, mu, spread) -> np.ndarray:
    """log p(y_u | mu_d, s_d) for every draw d and unit u, the unit's censored components
    integrated out (:func:`unit_marginal` on :func:`censored_grids`' ``grid``): (D, U). The
    importance ratio of unit u's leave-one-out posterior of (mu, s); a table at the sampled
    theta_u instead weighs each draw by that unit's own censored parameters too, which
    raises the Pareto k and with it the exact refits (benchmarks/RESULTS_pool.md)."""
    return np.asarray(_unit_log_lik_draws(jnp.asarray(y), jnp.asarray(cov), jnp.asarray(cens),
                                          jnp.asarray(mu), jnp.asarray(spread),
                                          *(jnp.asarray(a) for a in grid)))


#: :func:`unit_marginal` over units (inner) and draws (outer), compiled once per shape
_unit_log_lik_draws = program(jax.vmap(jax.vmap(unit_marginal,
                                                in_axes=(0, 0, 0, None, None, 0, 0, 0)),
                                       in_axes=(None, None, None, 0, 0, None, None, None)))


def _predictive_p(yu, cu, cens, mu, spread, log_w=None, test: str = "joint") -> float:
    """(Weighted) mean over draws of the unit's predictive p-values, Bonferroni-combined:
    P(chi2_Pr > d2) of its resolved components (d2 their Mahalanobis distance under
    S + Sigma_u), or with ``test="each"`` the two-sided normal p-value of each resolved
    component alone, and, per censored component, Phi((y_t - mu_t) / sqrt(s_t^2 + Sigma_tt)),
    the chance that a unit of the population measures that low."""
    r = cens == 0
    w = None if log_w is None else np.exp(log_w - np.max(log_w))
    mean = (lambda a: float(a.mean())) if w is None else (lambda a: float(np.sum(w * a) / np.sum(w)))  # noqa: E731
    ps = []
    if test == "each":
        for t in np.flatnonzero(r):
            z = (yu[t] - mu[:, t]) / np.sqrt(spread[:, t] ** 2 + cu[t, t])
            ps.append(mean(2.0 * norm_sf(np.abs(z))))
    elif r.any():
        A = cu[np.ix_(r, r)][None] + spread[:, r, None] * np.eye(int(r.sum())) * spread[:, None, r]
        d = yu[r][None] - mu[:, r]
        d2 = np.einsum("di,di->d", d, np.linalg.solve(A, d[..., None])[..., 0])
        ps.append(mean(chi2_sf(d2, int(r.sum()))))
    for t in np.flatnonzero(~r):
        ps.append(mean(norm_cdf((yu[t] - mu[:, t]) / np.sqrt(spread[:, t] ** 2 + cu[t, t]))))
    return min(1.0, len(ps) * min(ps))


#: leave-one-out by Pareto-smoothed importance sampling is trusted when its Pareto k is
#: below this (Vehtari, Gelman & Gabry 2017); otherwise, and near the flag level, the unit's
#: population is refitted without it
PARETO_K_MAX = 0.7
REFIT_FACTOR = 10.0


def fit_pool(y, cov, names, *, censored=None, ceiling=None, seed: int = 0,
             flag_level: float = 0.01, mu_prior=None, amplitude_scale=None, outliers: bool = True,
             outlier_test: str = "joint", unit_cov=None, start=None,
             num_warmup: int | None = None, num_samples: int = 1000,
             num_chains: int = 4) -> PoolResult:
    """Posterior of the population model (module docstring) from estimates ``y`` (U, P) with
    covariances ``cov`` (U, P, P), and each unit's leave-one-out outlier p-value.
    ``censored`` (U, P) marks components a unit does not resolve: y is then its estimate,
    ``ceiling`` (U, P) the log of the value at which the term alone is the unit's measured
    AVAR (required with ``censored``; raised to keep a _MIN_REST share for the other terms) and
    cov's block of them the covariance of their shifts x (:func:`censored_shift`, module
    docstring); their covariances with resolved components are ignored.
    ``mu_prior``: ``(mean (P,), sd (P,))`` of the normal prior on mu (a datasheet), or None.
    ``amplitude_scale`` (P,): where finite, the prior of that component is
    e^mu ~ HalfCauchy(0, amplitude_scale) instead (:func:`amplitude_log_prior`; the
    components are log amplitudes, module docstring).
    ``outliers=False`` skips the leave-one-out p-values (NaN). ``outlier_test``: ``"joint"``
    (chi-square of all resolved components) or ``"each"`` (each component alone; module
    docstring). ``unit_cov`` (U, P, P): the covariance of each unit's resolved components
    where the unit is taken alone -- its outlier test and its shrunk draws given the
    population -- when it differs from ``cov`` (the pool's model of the population);
    censored components keep ``cov``'s width. ``start``: the ``adaptation`` of a pool of
    the same units and terms with other covariances; its mass matrix and step size are
    kept (:data:`START_WARMUP`). ``num_warmup``: warm-up steps; None: WARMUP, or
    WARMUP_CENSORED where a component is censored.

    Leave-one-out: the full posterior's draws reweighted by 1 / p(y_u | mu, S) (PSIS,
    :func:`fogbayes.stats.psis.psislw`); a unit whose Pareto k exceeds PARETO_K_MAX or whose
    p-value lies within REFIT_FACTOR x ``flag_level`` is refitted exactly without it (the
    same compiled sampler with its weight set to 0, half the chains, keeping this posterior's
    adaptation: :func:`_start_without`), so a flag never rests on the approximation.
    """
    from ..stats.psis import psislw

    y = np.asarray(y, dtype=float)
    cov = np.asarray(cov, dtype=float)
    U, P = y.shape
    if U < 2:
        from ..errors import ArgumentError

        raise ArgumentError(f"a population needs at least two units, got {U}",
                            fix="pool two or more runs or units")
    cens = np.zeros((U, P)) if censored is None else np.asarray(censored, dtype=float)
    r = 1.0 - cens
    # no covariance between a unit's resolved and censored components
    both = r[:, :, None] * r[:, None, :] + cens[:, :, None] * cens[:, None, :]
    cov = cov * both
    ucov = cov if unit_cov is None else (
        np.asarray(unit_cov, dtype=float) * r[:, :, None] * r[:, None, :]
        + cov * cens[:, :, None] * cens[:, None, :])
    if cens.any() and ceiling is None:
        raise ValueError("censored components need their ceiling")
    ceil = y + 1.0 if ceiling is None else np.maximum(
        np.asarray(ceiling, dtype=float), y - 0.5 * np.log1p(-_MIN_REST))
    # the outlier test takes a censored component's log-space variance at its peak:
    # dx/dtheta = 2 v_hat / S there
    tcov = ucov.copy()
    for u, t in zip(*np.nonzero(cens)):
        tcov[u, t, t] = cov[u, t, t] / (2.0 * np.exp(2.0 * (y[u, t] - ceil[u, t]))) ** 2
    rng = np.random.default_rng(seed)
    centre, z0 = _start(y, cov, num_chains, rng)
    mu_sd = np.full(P, MU_PRIOR_SD)
    if mu_prior is not None:  # a datasheet: the typical unit's value and how loosely known
        centre, mu_sd = (np.asarray(a, dtype=float) for a in mu_prior)
    log_scale = np.full(P, np.nan) if amplitude_scale is None else np.log(
        np.asarray(amplitude_scale, dtype=float))
    key = jax.random.PRNGKey(seed)
    run = functools.partial(_run, y, cov, cens, ceil, centre=centre, mu_sd=mu_sd,
                            log_scale=log_scale, z0=z0,
                            num_warmup=num_warmup,
                            num_samples=num_samples, num_chains=num_chains)
    mu, spread, diagnostics, theta, adaptation = run(np.ones(U), key=key, start=start)
    if not outliers:
        diagnostics.update(pareto_k=[], loo_method=["none"] * U, refits=0, refits_converged=0)
        units = shrink(y, ucov, mu, spread, rng, cens, theta)
        new_unit = mu + spread * rng.standard_normal(mu.shape)
        return PoolResult(tuple(names), mu, spread, units, new_unit, np.full(U, np.nan),
                          diagnostics, adaptation)
    # leave-one-out on the posterior of (mu, s), the units' censored parameters integrated
    # out: the ratio 1 / p(y_u | mu, s)
    ll = _log_lik_table(y, cov, cens, censored_grids(y, cov, cens, ceil), mu, spread)
    log_w, k_hat = psislw(-ll.T)  # (U, D) log ratios 1 / p(y_u | draw); k > 0.7: refitted
    outlier_p, method = np.empty(U), []
    refits = []
    for u in range(U):
        p = _predictive_p(y[u], tcov[u], cens[u], mu, spread, log_w[u], outlier_test)
        if k_hat[u] > PARETO_K_MAX or p < REFIT_FACTOR * flag_level:
            w = np.ones(U)
            w[u] = 0.0
            # half the chains: the refit's draws serve one p-value, a mean over them (on
            # two cores the time of one chain instead of two)
            half = max(1, num_chains // 2)
            mu_u, s_u, diag_u, _, _ = run(w, key=jax.random.fold_in(key, u + 1),
                                          num_chains=half, start=_start_without(adaptation, u, P),
                                          z0={k: v[:half] for k, v in z0.items()})
            p = _predictive_p(y[u], tcov[u], cens[u], mu_u, s_u, test=outlier_test)
            refits.append(diag_u["converged"])
            method.append("refit")
        else:
            method.append("psis")
        outlier_p[u] = p
    diagnostics.update(pareto_k=k_hat.tolist(), loo_method=method, refits=len(refits),
                       refits_converged=int(sum(refits)))
    units = shrink(y, ucov, mu, spread, rng, cens, theta)
    new_unit = mu + spread * rng.standard_normal(mu.shape)
    return PoolResult(tuple(names), mu, spread, units, new_unit, outlier_p, diagnostics,
                      adaptation)
