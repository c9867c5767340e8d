r"""Hierarchical normal model of per-unit estimates: population, spread, shrunk units, outliers.

Each unit :math:`u = 1..U` (a sensor, or one run of a sensor) gives an estimate
:math:`y_u \in \mathbb R^P` of its own parameters :math:`\theta_u` with covariance
:math:`\Sigma_u` (its single-unit fit; for Allan terms the GLS fit in log space,
:func:`fogbayes.allan.fit.fit_wls`). The population model is

.. math::

    y_u \mid \theta_u \sim \mathcal N(\theta_u, \Sigma_u), \qquad
    \theta_u \sim \mathcal N(\mu, S), \quad S = \mathrm{diag}(s_1^2 .. s_P^2),

    \mu_p \sim \mathcal N(\tilde y_p, 10^2), \qquad s_p \sim \mathrm{HalfNormal}(1),

with :math:`\tilde y_p` the median of the units' estimates (the prior only fixes the scale:
10 in log space is a factor :math:`e^{10}`; a spread of 1 in log space is a factor 2.7
between units, so HalfNormal(1) admits anything a fleet of one type shows). A datasheet
says where the typical unit lies: with ``mu_prior = (m, sd)`` the prior of :math:`\mu_p` is
:math:`\mathcal N(m_p, sd_p^2)` instead (:mod:`fogbayes.inference.datasheet`: :math:`m_p`
the log of the sheet value, :math:`sd_p = \ln L_p / 1.645` for looseness :math:`L_p`). The unit
parameters integrate out exactly, :math:`y_u \sim \mathcal N(\mu, S + \Sigma_u)`, so NUTS
samples only :math:`(\mu, \log s)`: :math:`2P` dimensions and no funnel between a unit and
the spread. Given a draw of :math:`(\mu, S)` each unit's parameters are normal,

.. math::

    \theta_u \mid y, \mu, S \sim \mathcal N\big(\mu + S (S + \Sigma_u)^{-1} (y_u - \mu),\;
        S - S (S + \Sigma_u)^{-1} S\big),

drawn once per posterior draw (the shrunk per-unit posteriors). A new unit of the
population is :math:`\mathcal N(\mu, S)` (the population's predictive range).

Outliers: unit :math:`u` is judged against the population fitted *without* it (the same
sampler with that unit's weight set to 0, all leave-one-out fits in one vmapped call):
its posterior-predictive p-value is

.. math::

    p_u = \mathrm E_{\mu, S \mid y_{-u}}\Big[\Pr\big(\chi^2_P > (y_u - \mu)^\top
        (S + \Sigma_u)^{-1} (y_u - \mu)\big)\Big],

uniform for a unit of the population, over its resolved components; each censored
component (below) is judged one-sided, :math:`\Phi((y_{ut} - \mu_t)/\sqrt{s_t^2 +
\sigma_{ut}^2})`, and the smallest of these p-values times their number (Bonferroni) is the
unit's. It is flagged when :math:`p_u` is below the flag level.

With ``outlier_test="each"`` every resolved component is judged on its own instead, two-sided,
:math:`2\,\Phi(-|y_{ut} - \mu_t| / \sqrt{s_t^2 + \Sigma_{u,tt}})`, and the smallest of
all the components' p-values times their number is the unit's. It is the more powerful test
when one term of a unit is off and the others are not (a unit whose rate random walk is
5x its own, on the fleets of ``benchmarks/bench_pool.py``: detected in 90 of 100 at level
0.01 against 85 with the joint test, false flags 0.45 % against 0.8 %), the usual way a
unit of a type fails; the joint test is the more powerful when every component moves a
little (a shifted thermal curve), and stays the default.

The normal likelihood of :math:`y_u` is the approximation this module makes: the GLS
estimates of well-resolved Allan terms are close to normal in log space (their 90 %
intervals cover 85-95 %, benchmarks/RESULTS_allan.md). A term a unit does not resolve (its
interval reaches 0) is not: its likelihood is flat towards 0 and falls off above. Such a
*censored* component :math:`t` of unit :math:`u` gets the flat-below likelihood

.. math::

    L_{ut}(\theta) = 1 \ (\theta \le y_{ut}), \qquad
    \exp\!\big(-(\theta - y_{ut})^2 / (2\sigma_{ut}^2)\big) \ (\theta > y_{ut}),

with :math:`y_{ut}` the unit's estimate and :math:`\sigma_{ut}` the width of its interval's
upper side, independent of its other components; its integral against
:math:`\mathcal N(\mu_t, s_t^2)` is closed-form (:func:`_censored_log_lik`). Treating such a
unit as a normal measurement at its (low, arbitrary) estimate put the population K 8 % high
with 73 % coverage on simulated fleets (benchmarks/RESULTS_pool.md; 80 % with this
likelihood). The width sigma comes from the interval's upper end, which may be the fit's
99.9 % cap (:func:`fogbayes.allan.fit.upper_caps`): the limit is then a little
tighter than a 95 % one.
"""

from __future__ import annotations

from ..inference.convergence import converged
import functools
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from scipy import stats

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


def _censored_log_lik(y, sig2, mu, s):
    """log of the integral of L(theta) N(theta; mu, s^2) over theta, for the flat-below
    likelihood L = 1 for theta <= y and exp(-(theta - y)^2 / (2 sig2)) above:

        Phi((y - mu) / s) + sqrt(sig2 / (sig2 + s^2)) exp(-(y - mu)^2 / (2 (sig2 + s^2)))
                             Phi((mu - y) sqrt(sig2) / (s sqrt(sig2 + s^2)))
    """
    from jax.scipy.special import log_ndtr

    tot = sig2 + s**2
    below = log_ndtr((y - mu) / s)
    above = (0.5 * jnp.log(sig2 / tot) - 0.5 * (y - mu) ** 2 / tot
             + log_ndtr((mu - y) * jnp.sqrt(sig2) / (s * jnp.sqrt(tot))))
    return jnp.logaddexp(below, above)


def unit_log_lik(yu, cu, cens, mu, s):
    """log p(y_u | mu, s), the unit's parameters integrated out: its resolved components
    N(y_r; mu_r, Sigma_rr + S_rr), times each censored component's flat-below likelihood
    (:func:`_censored_log_lik`; a censored component has no covariance with the others)."""
    r = 1.0 - cens
    A = (cu + jnp.diag(s**2)) * jnp.outer(r, r) + jnp.diag(cens)
    L = jnp.linalg.cholesky(A)
    z = jax.scipy.linalg.solve_triangular(L, (yu - mu) * r, lower=True)
    gauss = (-0.5 * z @ z - jnp.sum(jnp.log(jnp.diag(L)))
             - 0.5 * jnp.sum(r) * jnp.log(2 * jnp.pi))
    return gauss + jnp.sum(cens * _censored_log_lik(yu, jnp.diag(cu), mu, s))


def _log_marginal(y, cov, cens, w, mu, s):
    """sum_u w_u log p(y_u | mu, s)."""
    return jnp.sum(w * jax.vmap(unit_log_lik, in_axes=(0, 0, 0, None, None))(y, cov, cens, mu, s))


def _potential(y, cov, cens, w, centre, mu_sd):
    from jax.scipy.stats import norm

    def potential(z):
        mu, log_s = z["mu"], z["log_s"]
        s = jnp.exp(log_s)
        lp = jnp.sum(norm.logpdf(mu, centre, mu_sd))
        # HalfNormal(1) on s, sampled as log s (+ the Jacobian log s)
        lp += jnp.sum(norm.logpdf(s, 0.0, SPREAD_PRIOR_SD) + jnp.log(2.0) + log_s)
        return -(lp + _log_marginal(y, cov, cens, w, mu, s))

    return potential


@functools.lru_cache(maxsize=8)
def _sampler(num_warmup: int, num_samples: int):
    """NUTS chains over (mu, log s) (:mod:`fogbayes.inference.nuts`); the unit weights are an
    argument, so the full fit and every leave-one-out refit share one compilation per (U, P)."""
    from ..inference.nuts import chain_sampler

    return chain_sampler(_potential, num_warmup, num_samples, target_accept_prob=0.98)


def _start(y, cov, num_chains, rng):
    """Chains start near the precision-weighted mean and the spread of the estimates."""
    centre = np.median(y, axis=0)
    spread = np.maximum(np.std(y, axis=0), 0.05)
    mu0 = centre + 0.1 * spread * rng.standard_normal((num_chains, y.shape[1]))
    ls0 = np.log(spread) + 0.1 * rng.standard_normal((num_chains, y.shape[1]))
    return centre, {"mu": jnp.asarray(mu0), "log_s": jnp.asarray(ls0)}


def _summary(zs, div) -> dict:
    from numpyro.diagnostics import summary

    diag = summary({"mu": zs["mu"], "log_s": zs["log_s"]}, group_by_chain=True)
    r_hat = max(float(np.max(diag[k]["r_hat"])) for k in ("mu", "log_s"))
    ess = min(float(np.min(diag[k]["n_eff"])) for k in ("mu", "log_s"))
    divergences = int(np.asarray(div).sum())
    return {"r_hat_max": r_hat, "ess_min": ess, "divergences": divergences,
            "converged": converged(r_hat, ess, divergences, floor=ESS_MIN)}


def shrink(y, cov, mu, spread, rng, cens=None) -> np.ndarray:
    """Draws of each unit's parameters given population draws (see the module docstring).

    ``y`` (U, P), ``cov`` (U, P, P), ``mu``/``spread`` (D, P) -> (D, U, P). A censored
    component (``cens``) is independent of the others: drawn from N(mu_t, s_t^2) and kept
    with probability L(theta) (the flat-below likelihood; rejection sampling, 64 proposals,
    the likeliest kept if none is accepted)."""
    U, P = y.shape
    cens = np.zeros((U, P)) if cens is None else np.asarray(cens, dtype=float)
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
    for u, t in zip(*np.nonzero(cens)):
        D = mu.shape[0]
        prop = mu[:, t, None] + spread[:, t, None] * rng.standard_normal((D, 64))
        lik = np.exp(-0.5 * np.clip(prop - y[u, t], 0, None) ** 2 / cov[u, t, t])
        ok = rng.random((D, 64)) < lik
        pick = np.where(ok.any(axis=1), ok.argmax(axis=1), lik.argmax(axis=1))
        out[:, u, t] = prop[np.arange(D), pick]
    return out


def _run(y, cov, cens, w, centre, mu_sd, z0, key, num_warmup, num_samples, num_chains):
    """One posterior of (mu, s) with unit weights ``w``: draws (D, P) twice, diagnostics."""
    keys = jax.random.split(key, num_chains)
    zs, div = _sampler(num_warmup, num_samples)(keys, z0, jnp.asarray(y), jnp.asarray(cov),
                                               jnp.asarray(cens), jnp.asarray(w),
                                               jnp.asarray(centre), jnp.asarray(mu_sd))
    zs = {k: np.asarray(v) for k, v in zs.items()}
    P = y.shape[1]
    return zs["mu"].reshape(-1, P), np.exp(zs["log_s"]).reshape(-1, P), _summary(zs, div)


def _log_lik_table(y, cov, cens, mu, spread) -> np.ndarray:
    """log p(y_u | mu_d, s_d) for every draw d and unit u: (D, U)."""
    return np.asarray(_unit_log_lik_draws(jnp.asarray(y), jnp.asarray(cov), jnp.asarray(cens),
                                          jnp.asarray(mu), jnp.asarray(spread)))


#: :func:`unit_log_lik` over units (inner) and draws (outer), compiled once per shape
_unit_log_lik_draws = program(jax.vmap(jax.vmap(unit_log_lik, in_axes=(0, 0, 0, None, None)),
                                       in_axes=(None, None, None, 0, 0)))


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
            ps.append(mean(2.0 * stats.norm.sf(np.abs(z))))
    elif r.any():
        A = cu[np.ix_(r, r)][None] + spread[:, r, None] * np.eye(int(r.sum())) * spread[:, None, r]
        d = yu[r][None] - mu[:, r]
        d2 = np.einsum("di,di->d", d, np.linalg.solve(A, d[..., None])[..., 0])
        ps.append(mean(stats.chi2.sf(d2, int(r.sum()))))
    for t in np.flatnonzero(~r):
        ps.append(mean(stats.norm.cdf((yu[t] - mu[:, t]) / np.sqrt(spread[:, t] ** 2 + cu[t, t]))))
    return min(1.0, len(ps) * min(ps))


#: leave-one-out by Pareto-smoothed importance sampling is trusted when its Pareto k is
#: below this (Vehtari, Gelman & Gabry 2017); otherwise, and near the flag level, the unit's
#: population is refitted without it
PARETO_K_MAX = 0.7
REFIT_FACTOR = 10.0


def fit_pool(y, cov, names, *, censored=None, seed: int = 0, flag_level: float = 0.01,
             mu_prior=None, outliers: bool = True, outlier_test: str = "joint", unit_cov=None,
             num_warmup: int = 500, num_samples: int = 1000, num_chains: int = 4) -> PoolResult:
    """Posterior of the population model (module docstring) from estimates ``y`` (U, P) with
    covariances ``cov`` (U, P, P), and each unit's leave-one-out outlier p-value.
    ``censored`` (U, P) marks components a unit does not resolve: y is then its estimate
    and cov[t, t] the squared log-space width of its upper side (the flat-below likelihood,
    module docstring); their covariances with other components are ignored.
    ``mu_prior``: ``(mean (P,), sd (P,))`` of the normal prior on mu (a datasheet), or None.
    ``outliers=False`` skips the leave-one-out p-values (NaN). ``outlier_test``: ``"joint"``
    (chi-square of all resolved components) or ``"each"`` (each component alone; module
    docstring). ``unit_cov`` (U, P, P): the covariance of each unit's resolved components
    where the unit is taken alone -- its outlier test and its shrunk draws given the
    population -- when it differs from ``cov`` (the pool's model of the population);
    censored components keep ``cov``'s width.

    Leave-one-out: the full posterior's draws reweighted by 1 / p(y_u | mu, S) (PSIS,
    ArviZ); a unit whose Pareto k exceeds PARETO_K_MAX or whose p-value lies within
    REFIT_FACTOR x ``flag_level`` is refitted exactly without it (the same compiled sampler
    with its weight set to 0), so a flag never rests on the approximation.
    """
    import warnings

    import arviz as az

    y = np.asarray(y, dtype=float)
    cov = np.asarray(cov, dtype=float)
    U, P = y.shape
    if U < 2:
        from ..errors import ArgumentError

        raise ArgumentError(f"a population needs at least two units, got {U}",
                            fix="pool two or more runs or units")
    cens = np.zeros((U, P)) if censored is None else np.asarray(censored, dtype=float)
    r = 1.0 - cens
    cov = cov * r[:, :, None] * r[:, None, :] + np.eye(P) * (cens * np.diagonal(cov, axis1=1, axis2=2))[:, None, :]
    ucov = cov if unit_cov is None else (
        np.asarray(unit_cov, dtype=float) * r[:, :, None] * r[:, None, :]
        + np.eye(P) * (cens * np.diagonal(cov, axis1=1, axis2=2))[:, None, :])
    rng = np.random.default_rng(seed)
    centre, z0 = _start(y, cov, num_chains, rng)
    mu_sd = np.full(P, MU_PRIOR_SD)
    if mu_prior is not None:  # a datasheet: the typical unit's value and how loosely known
        centre, mu_sd = (np.asarray(a, dtype=float) for a in mu_prior)
    key = jax.random.PRNGKey(seed)
    run = functools.partial(_run, y, cov, cens, centre=centre, mu_sd=mu_sd, z0=z0,
                            num_warmup=num_warmup,
                            num_samples=num_samples, num_chains=num_chains)
    mu, spread, diagnostics = run(np.ones(U), key=key)
    if not outliers:
        diagnostics.update(pareto_k=[], loo_method=["none"] * U, refits=0, refits_converged=0)
        units = shrink(y, ucov, mu, spread, rng, cens)
        new_unit = mu + spread * rng.standard_normal(mu.shape)
        return PoolResult(tuple(names), mu, spread, units, new_unit, np.full(U, np.nan),
                          diagnostics)
    ll = _log_lik_table(y, cov, cens, mu, spread)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # ArviZ warns on k > 0.7: handled by refitting
        log_w, k_hat = az.psislw(-ll.T)  # (U, D) log ratios 1 / p(y_u | draw)
    log_w, k_hat = np.asarray(log_w), np.asarray(k_hat)
    outlier_p, method = np.empty(U), []
    refits = []
    for u in range(U):
        p = _predictive_p(y[u], ucov[u], cens[u], mu, spread, log_w[u], outlier_test)
        if k_hat[u] > PARETO_K_MAX or p < REFIT_FACTOR * flag_level:
            w = np.ones(U)
            w[u] = 0.0
            mu_u, s_u, diag_u = run(w, key=jax.random.fold_in(key, u + 1))
            p = _predictive_p(y[u], ucov[u], cens[u], mu_u, s_u, test=outlier_test)
            refits.append(diag_u["converged"])
            method.append("refit")
        else:
            method.append("psis")
        outlier_p[u] = p
    diagnostics.update(pareto_k=k_hat.tolist(), loo_method=method, refits=len(refits),
                       refits_converged=int(sum(refits)))
    units = shrink(y, ucov, mu, spread, rng, cens)
    new_unit = mu + spread * rng.standard_normal(mu.shape)
    return PoolResult(tuple(names), mu, spread, units, new_unit, outlier_p, diagnostics)
