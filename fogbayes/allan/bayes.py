"""NumPyro posterior of the five-term Allan model, with correlated AVAR estimates.

Wilson-Hilferty z_j = ((s2hat_j / s2_j)^(1/3) - 1 + v_j) / sqrt(v_j), v_j = 2 / (9 nu_j), z ~ N(0, C)
(Gaussian copula): log p = log N(z; 0, C) + sum_j log|dz_j / ds2hat_j|, with nu and C at theta
(:mod:`fogbayes.stats.allan_cov`). Priors theta_p ~ HalfNormal(3 e^{l_p}) (data scale); with a
datasheet (:mod:`fogbayes.inference.datasheet`) log theta_p ~ N(log v_p, (ln L_p / 1.645)^2). A failed fit
(z'C^-1 z beyond chi2_K 99.9 %) is refitted with a log-normal discrepancy HalfNormal(0.05).
:func:`select_terms`: PSIS-LOO over the sequential factors p(s2hat_j | s2hat_<j, theta).
"""

from __future__ import annotations

import functools
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from ..support.tails import chi2_sf
from .model import TERMS, AllanParams, adev
from .data import AllanFitData, cube_root_normal, model_moments
from .fit import AllanFit, _estimates, _mask, fit_wls
from ..inference.convergence import converged as rule
from ..inference.nuts import on_host
from ..support.stored import stored

#: bulk-ESS floor of the convergence rule: 200 in all (the K-R ridge mixes slowly)
ESS_FLOOR = 200.0

#: draws per chain of a reported posterior (:func:`fit_bayes`)
NUM_SAMPLES = 2000

PRIOR_SCALE = 3.0
DELTA_SCALE = 0.05
GOF_LEVEL = 1e-3


def _copula(logp, delta, mask, data, obs):
    mean, nu, corr = model_moments(logp, mask, data, delta)
    z, log_jac = cube_root_normal(obs, mean, nu)
    K = z.shape[0]
    L = jnp.linalg.cholesky(corr + 1e-10 * jnp.eye(K))
    w = jax.scipy.linalg.solve_triangular(L, z, lower=True)
    total = (-0.5 * w @ w - jnp.sum(jnp.log(jnp.diag(L))) - 0.5 * K * jnp.log(2 * jnp.pi)
             + jnp.sum(log_jac))
    return total, z, log_jac, L


def log_likelihood(logp, delta, mask, data: AllanFitData, obs):
    """Total log-likelihood and its K sequential terms log p(x_j | x_1 .. x_{j-1}).

    With the Cholesky factor L of the copula correlation (taus from short to long), the
    whitened w = L^-1 z are independent: term j = log N(w_j) - log L_jj + log|dz_j/dx_j|, and
    the terms add up to the total. Each long-tau estimate is thus scored as a prediction from
    the shorter ones, which is what tells a K or R term from none; the symmetric leave-one-out
    conditionals p(x_j | x_-j) do not, because neighbouring taus (correlation ~0.9 under rate
    random walk) predict each other whatever the model.
    """
    total, z, log_jac, L = _copula(logp, delta, mask, data, obs)
    w = jax.scipy.linalg.solve_triangular(L, z, lower=True)
    pointwise = -0.5 * w**2 - 0.5 * jnp.log(2 * jnp.pi) - jnp.log(jnp.diag(L)) + log_jac
    return total, pointwise


#: times the sampler was traced (a Python side effect runs only while JAX traces): a second
#: datasheet, or none, with the same sizes and data shape leaves it as is
TRACES = {"sampler": 0}


def no_sheet() -> tuple:
    """The sampler's datasheet arguments without a sheet: every term half-normal."""
    return (jnp.zeros(5), jnp.zeros(5), jnp.ones(5))


def sheet_args(prior) -> tuple:
    """(on, mu, sd) of a :class:`~.datasheet.DatasheetPrior` (or None) as sampler arguments."""
    if prior is None:
        return no_sheet()
    return tuple(jnp.asarray(a) for a in prior.arrays())


def log_prior(logp, prior_loc, sheet):
    """Log prior density of the log-parameters, per term (5,), Jacobian included.

    Half-normal terms: log HalfNormal(e^logp; 3 e^prior_loc) + logp. Sheet terms (``on``):
    log N(logp; mu, sd) -- the log-normal density of theta = e^logp times theta.
    """
    from jax.scipy.stats import norm

    on, mu, sd = sheet
    scale = PRIOR_SCALE * jnp.exp(jnp.asarray(prior_loc))
    half = norm.logpdf(jnp.exp(logp), 0.0, scale) + jnp.log(2.0) + logp
    return jnp.where(on > 0, norm.logpdf(logp, mu, sd), half)


def _potential_gen(obs, mask, data, sheet, *, discrepancy: bool):
    """Negative log posterior in unconstrained space (``log_delta`` for the discrepancy)."""
    from jax.scipy.stats import norm

    def potential(z):
        logp = z["logp"]
        # half-normal (or the sheet's log-normal) prior on each parameter, sampled as its log
        lp = jnp.sum(log_prior(logp, data.prior_loc, sheet))
        delta = 0.0
        if discrepancy:  # HalfNormal(DELTA_SCALE) on delta, sampled as log delta
            delta = jnp.exp(z["log_delta"])
            lp += norm.logpdf(delta, 0.0, DELTA_SCALE) + jnp.log(2.0) + z["log_delta"]
        return -(lp + _copula(logp, delta, mask, data, obs)[0])

    return potential


@functools.lru_cache(maxsize=8)
def _sampler(num_warmup: int, num_samples: int, discrepancy: bool, warm_start: bool = False):
    """Warmup + sampling of NUTS chains as one jitted, chain-vmapped function.

    Built with NumPyro's functional ``hmc`` API and compiled once per configuration and data
    shape: the data and the datasheet prior are arguments, so fitting another record of the
    same length, or with another sheet or none, reuses it. It returns the chains' adapted
    mass and step size too; ``warm_start``: its first argument is such an adaptation, and
    the warm-up adapts the step size only (:func:`fogbayes.inference.nuts.chain_sampler`).
    """
    from ..inference.nuts import chain_sampler

    def traced():
        TRACES["sampler"] += 1

    # target acceptance 0.95, not 0.9: on 10 seeds of the test's four-term record (500 + 1000
    # draws, 2 chains) 0.9 left a divergence in 1 run and R-hat 1.010 in another (which run
    # depends on the CPU's floating point); 0.95 gave none, R-hat <= 1.0064, ESS >= 490
    # chains in threads: each runs its own trees (vmapped, every step waits for the deeper
    # of the two), a single chain traces and compiles in half a vmap's time, and the two
    # use both cores: 2.2-2.5 s against 3.9-6.4 s a five-term fit on the bench's record
    return chain_sampler(functools.partial(_potential_gen, discrepancy=discrepancy),
                         num_warmup, num_samples, target_accept_prob=0.95, on_trace=traced,
                         chain_method="threads", store_key=("allan.bayes", discrepancy),
                         warm_start=warm_start, return_adaptation=True)


class AllanPosterior(NamedTuple):
    """Posterior of the five-term model: summary fit, draws and what model checking needs."""

    fit: AllanFit           # method "bayes": medians and 90 % credible intervals
    draws: np.ndarray       # (chains * draws, 5) canonical parameters (0 for absent terms)
    log_lik: np.ndarray     # (chains, draws, K) pointwise LOO conditional log densities
    diagnostics: dict       # r_hat, ess, divergences, goodness of fit, discrepancy used
    mask: np.ndarray        # (5,) terms in the model
    data: AllanFitData
    adaptation: tuple = None  # the chains' mean inverse mass of log p (5, 5), step size


#: warm-up steps of a drop-one model started from the current model's adaptation
#: (:func:`select_terms`; step size only): benchmarks/RESULTS_allan.md section 3's selection
#: check chose the same terms with it as with 500 steps from the Laplace mass on 60 of 60
TRIAL_WARMUP = 100
#: variance of log|x| for a normal x: an absent term's log under its half-normal prior, the
#: mass a drop-one model gives the term it drops
_LOG_HALF_NORMAL_VAR = np.pi ** 2 / 8


def fit_bayes(data: AllanFitData, terms=TERMS, *, seed: int, num_warmup: int = 500,
              num_samples: int = NUM_SAMPLES, num_chains: int = 2,
              discrepancy: str | bool = "auto", prior=None, start=None,
              start_warmup: int = TRIAL_WARMUP) -> AllanPosterior:
    """Sample the posterior (NUTS, started at the GLS estimate); see the module docstring.

    ``prior``: a :class:`~.datasheet.DatasheetPrior` (or a prior document, or its path): a
    log-normal prior on each term the sheet gives; None: half-normal priors throughout.
    ``start``: ``(inverse_mass (5, 5), step_size)`` of log p from a related posterior
    (:func:`select_terms`): ``start_warmup`` warm-up steps that adapt the step size only,
    instead of ``num_warmup`` from the Laplace mass (a discrepancy refit warms up in full).

    Default sizes, 500 warm-up / 2000 draws per chain: the K-R ridge mixes slowly, so the draws
    are what ESS > 200 needs; with the warm-up starting at the Laplace mass
    (:func:`fogbayes.inference.nuts.laplace_inverse_mass`) 500 warm-up steps converge as often
    as 1000 (benchmarks/RESULTS_allan.md section 3, "Posterior coverage and convergence").
    """
    from ..inference.datasheet import as_prior

    prior = as_prior(prior)
    mask = _mask(terms)
    wls = fit_wls(data, terms)
    if discrepancy is True:
        start = None
    post = _run(data, mask, wls.info["logp"], seed,
                num_warmup if start is None else start_warmup, num_samples, num_chains,
                discrepancy is True, prior, start)
    if discrepancy == "auto" and post.diagnostics["gof_p"] < GOF_LEVEL:
        post = _run(data, mask, wls.info["logp"], seed, num_warmup, num_samples, num_chains,
                    True, prior)
    return post


def _pointwise_loglik_traced(logp, delta, mask, data: AllanFitData, obs):
    """log p(obs_k | draw) of every draw and lag: logp (C, D, 5), delta (C, D) -> (C, D, K).
    The data are arguments (one compiled program per shape, not per record)."""
    def one(lp, d):
        return log_likelihood(lp, d, mask, data, obs)[1]

    return jax.vmap(jax.vmap(one))(logp, delta)


# kept on disk once traced, run on the CPU like the samplers: tracing it was 0.27 s of
# every `fogbayes allan --bayes`
_pointwise_loglik = on_host(stored(_pointwise_loglik_traced, ("allan.pointwise_loglik",)))


def _run(data, mask, init_logp, seed, num_warmup, num_samples, num_chains, discrepancy,
         prior=None, start=None):
    from numpyro.diagnostics import summary

    init = np.clip(init_logp, data.prior_loc - 12.0, data.prior_loc + np.log(3 * PRIOR_SCALE))
    sheet = sheet_args(prior)
    if prior is not None:  # sheet terms start within 3 prior sd of the sheet value
        given, mu, sd = (np.asarray(a) for a in sheet)
        init = np.where(given > 0, np.clip(init_logp, mu - 3 * sd, mu + 3 * sd), init)
    rng = np.random.default_rng(seed)  # chains start at jittered copies of the GLS estimate
    z0 = {"logp": jnp.asarray(init + 0.01 * rng.standard_normal((num_chains, 5)))}
    if discrepancy:
        z0["log_delta"] = jnp.full(num_chains, np.log(0.01))
    obs, jmask = jnp.asarray(data.avar), jnp.asarray(mask)
    keys = jax.random.split(jax.random.PRNGKey(seed), num_chains)
    lead = () if start is None else ((jnp.asarray(start[0]), jnp.asarray(start[1])),)
    zs, div, (inverse_mass, step_size) = _sampler(
        num_warmup, num_samples, bool(discrepancy), start is not None)(
        keys, z0, *lead, obs, jmask, data, sheet)
    # z is raveled in key order: "log_delta" (when sampled) comes before "logp"
    skip = 1 if discrepancy else 0
    adaptation = (np.asarray(inverse_mass).mean(axis=0)[skip:, skip:],
                  float(np.exp(np.mean(np.log(np.asarray(step_size))))))
    samples = {"logp": zs["logp"]}
    logp = np.asarray(zs["logp"])  # (chains, draws, 5)
    delta = np.exp(np.asarray(zs["log_delta"])) if discrepancy else np.zeros(logp.shape[:2])
    # in pieces of the drop-one models' draws: one program serves every posterior of a call
    n_draws = logp.shape[1]
    step = TRIAL_SAMPLES_MIN if n_draws % TRIAL_SAMPLES_MIN == 0 else n_draws
    log_lik = np.concatenate([np.asarray(_pointwise_loglik(
        jnp.asarray(logp[:, i:i + step]), jnp.asarray(delta[:, i:i + step]), jmask, data, obs))
        for i in range(0, n_draws, step)], axis=1)
    diag = summary(samples, group_by_chain=True)["logp"]
    on = mask > 0
    draws = np.exp(logp.reshape(-1, 5)) * mask
    med = np.median(draws, axis=0)
    lo, hi = np.quantile(draws, [0.05, 0.95], axis=0)
    gof = _goodness_of_fit(np.log(med[on]), mask, data, obs, float(np.median(delta)))
    divergences = int(np.asarray(div).sum())
    r_hat = float(np.max(np.asarray(diag["r_hat"])[on]))
    ess = float(np.min(np.asarray(diag["n_eff"])[on]))
    converged = rule(r_hat, ess, divergences, floor=ESS_FLOOR)
    diagnostics = {"r_hat_max": r_hat, "ess_min": ess, "divergences": divergences,
                   "gof_stat": gof[0], "gof_p": gof[1], "discrepancy": bool(discrepancy),
                   "delta_median": float(np.median(delta)), "converged": converged,
                   "prior": "half-normal" if prior is None else
                   "datasheet: log-normal on " + ", ".join(prior.terms) + ", half-normal on "
                   "the others"}
    fit = AllanFit("bayes", _estimates(med, lo, hi, mask), AllanParams(*med), converged,
                   diagnostics)
    return AllanPosterior(fit, draws, log_lik, diagnostics, mask, data, adaptation)


def _start_without(post: AllanPosterior, term: str) -> tuple:
    """Where a model lacking ``term`` starts its warm-up: ``post``'s adaptation with the
    term's row and column replaced by its prior variance (the term no longer meets the data)."""
    inverse_mass, step_size = post.adaptation
    i = TERMS.index(term)
    inverse_mass = np.array(inverse_mass)
    inverse_mass[i, :] = inverse_mass[:, i] = 0.0
    inverse_mass[i, i] = _LOG_HALF_NORMAL_VAR
    return inverse_mass, step_size


def _goodness_of_fit(logp_on, mask, data, obs, delta):
    logp = np.array(data.prior_loc, dtype=float)
    logp[mask > 0] = logp_on
    mean, nu, corr = model_moments(logp, np.asarray(mask, dtype=float), data, delta)
    z, _ = cube_root_normal(np.asarray(obs), mean, nu)
    stat = float(z @ np.linalg.solve(corr, z))
    return stat, float(chi2_sf(stat, len(obs)))


def posterior_band(post: AllanPosterior, tau, *, ci: float = 0.9, max_draws: int = 1000):
    """Quantiles (low, median, high) of the model ADEV sigma(tau) over the posterior draws."""
    tau = np.asarray(tau, dtype=float)
    step = max(1, post.draws.shape[0] // max_draws)
    curves = adev(tuple(post.draws[::step].T[:, :, None]), tau[None, :])  # (draws, taus)
    return tuple(np.quantile(curves, [0.5 - ci / 2, 0.5, 0.5 + ci / 2], axis=0))


def predictive_band(post: AllanPosterior, *, ci: float = 0.9, seed: int = 0):
    """Posterior-predictive interval of a new ADEV estimate at each fitted tau."""
    rng = np.random.default_rng(seed)
    logp = np.log(np.where(post.mask > 0, np.maximum(post.draws, 1e-300), 1.0))
    sel = logp[:: max(1, logp.shape[0] // 1000)]
    mask = np.asarray(post.mask, dtype=float)
    mean, nu = (np.stack(a) for a in zip(*(model_moments(lp, mask, post.data)[:2]
                                           for lp in sel)))
    v = 2.0 / (9.0 * nu)
    z = rng.standard_normal(mean.shape)
    sims = np.sqrt(mean * np.clip(1 - v + np.sqrt(v) * z, 0, None) ** 3)
    return tuple(np.quantile(sims, [0.5 - ci / 2, 0.5 + ci / 2], axis=0))


class TermSelection(NamedTuple):
    """Which terms the data support, by PSIS-LOO (and WAIC) against drop-one models."""

    present: tuple          # supported terms
    table: list             # one row per comparison: elpd differences, their se, decision
    full: AllanPosterior    # the posterior of the model with every candidate term
    selected: AllanPosterior  # the posterior of the model with the supported terms


#: a term is dropped when removing it costs less than this elpd (LOO); 2 elpd is an evidence
#: ratio of ~7. Dropping a real term biases the others while keeping a superfluous one only
#: widens intervals, so the bar is lower than the ~4 at which LOO differences become
#: clearly distinguishable (Sivula, Magnusson & Vehtari 2022).
ELPD_THRESHOLD = 2.0
#: fewest draws per chain of a drop-one model in :func:`select_terms`
TRIAL_SAMPLES_MIN = 500
#: terms whose posterior 5 % quantile explains this share of the AVAR somewhere are kept
#: without a comparison (their LOO difference would be hundreds)
OBVIOUS_SHARE = 0.25


def _loo(post: AllanPosterior):
    """PSIS-LOO and WAIC of the posterior's lags, with the chains' relative efficiency as
    ArviZ takes it (:func:`fogbayes.stats.mcmc.relative_efficiency` of the draws)."""
    from ..inference.compare import information
    from ..stats.mcmc import relative_efficiency

    chains, draws = post.log_lik.shape[:2]
    reff = relative_efficiency([post.draws.reshape(chains, draws, 5)])
    ll = post.log_lik.reshape(chains * draws, -1)
    return information(ll, "loo", reff), information(ll, "waic")


def _obvious(post: AllanPosterior) -> np.ndarray:
    from .model import term_avar

    low = np.quantile(post.draws, 0.05, axis=0)
    share = np.asarray(term_avar(tuple(low), post.data.tau)) / post.data.avar[None, :]
    return share.max(axis=1) >= OBVIOUS_SHARE


def _compare(scores_a, post_b: AllanPosterior) -> dict:
    """elpd(a) - elpd(b) by PSIS-LOO (pointwise se) and WAIC; ``scores_a``: ``_loo(a)``."""
    from ..inference.compare import difference

    loo_a, waic_a = scores_a
    loo_b, waic_b = _loo(post_b)
    d, se = difference(loo_a, loo_b)
    return {"d_elpd_loo": d, "se": se, "d_elpd_waic": waic_a.elpd - waic_b.elpd,
            "pareto_k_max": max(loo_a.pareto_k_max, loo_b.pareto_k_max)}


def select_terms(data: AllanFitData, terms=TERMS, *, seed: int, prior=None,
                 trial_samples: int | None = None, trial_warmup: int | None = None,
                 **kw) -> TermSelection:
    """Backward elimination by PSIS-LOO.

    From the model with all ``terms``: fit each model that lacks one candidate term, drop the
    term whose removal costs least if that cost ``elpd(with) - elpd(without)`` is below
    ELPD_THRESHOLD, and repeat from the reduced model. One term at a time matters: K and R
    can stand in for each other, so each alone looks unnecessary while one of them is needed.
    Terms that are obviously present (OBVIOUS_SHARE) are not candidates, nor are the terms
    a datasheet ``prior`` gives (the sheet says they exist; every fit uses the prior).

    The drop-one models are compared, not reported: they draw ``trial_samples`` per chain
    (default a quarter of ``num_samples``, at least TRIAL_SAMPLES_MIN): the elpd
    differences' Monte Carlo sd stays well below ELPD_THRESHOLD (a mix-A record of
    benchmarks/coverage_allan.py, six sampler seeds: 0.28-0.50 at 500 draws, 0.18-0.47 at
    2000). Each starts from the current model's adapted mass matrix (the dropped term's
    row and column set to its prior variance) and step size, and its ``trial_warmup``
    warm-up steps (default TRIAL_WARMUP) adapt the step size only: one term less leaves
    the others' posterior geometry nearly as it was, and a full warm-up from the Laplace
    mass was ~45 % of all leapfrog steps (benchmarks/RESULTS_allan.md section 3). The full
    model and the selected one are sampled at ``num_samples`` after a full warm-up: theirs
    are the reported intervals.
    """
    import warnings

    from ..inference.datasheet import as_prior

    prior = as_prior(prior)
    kw["prior"] = prior
    full_samples = kw.pop("num_samples", NUM_SAMPLES)
    if trial_samples is None:
        trial_samples = max(TRIAL_SAMPLES_MIN, full_samples // 4)
    trial_samples = min(trial_samples, full_samples)
    trial_kw = dict(kw, start_warmup=TRIAL_WARMUP if trial_warmup is None else trial_warmup)
    sheet_terms = () if prior is None else tuple(prior.terms)
    current = [t for t in TERMS if t in terms]
    post = fit_bayes(data, current, seed=seed, num_samples=full_samples, **kw)
    full, table = post, []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # Pareto-k / WAIC variance warnings: k is reported
        while True:
            obvious = _obvious(post)
            cands = [t for t in current
                     if not obvious[TERMS.index(t)] and t not in sheet_terms]
            if not cands:
                break
            trials = {t: fit_bayes(data, [u for u in current if u != t], seed=seed,
                                   num_samples=trial_samples, start=_start_without(post, t),
                                   **trial_kw) for t in cands}
            scores = _loo(post)  # the current model's, once for every candidate
            costs = {t: _compare(scores, trials[t]) for t in cands}
            worst = min(cands, key=lambda t: costs[t]["d_elpd_loo"])
            for t in cands:
                table.append({"term": t, "model": "+".join(current), **costs[t]})
            if costs[worst]["d_elpd_loo"] >= ELPD_THRESHOLD:
                break
            current.remove(worst)
            table.append({"term": worst, "model": "+".join(current + [worst]),
                          "decided": f"dropped (d_elpd_loo < {ELPD_THRESHOLD:g})"})
            post = trials[worst]
    if post is not full and trial_samples != full_samples:  # the reported model: full draws
        post = fit_bayes(data, current, seed=seed, num_samples=full_samples, **kw)
    return TermSelection(tuple(current), table, full, post)


def reported_terms(sel: TermSelection) -> dict:
    """What a selection reports per term: the selected model's median and 90 % interval for a
    present term; for an absent term value 0 and the interval [0, 95 % quantile of the full
    model] (an upper bound). Each :class:`~.allan_fit.TermEstimate` is paired with a flag."""
    from .model import UNITS
    from .fit import TermEstimate

    out = {}
    full_hi = np.quantile(sel.full.draws, 0.95, axis=0)
    for i, t in enumerate(TERMS):
        if t in sel.present:
            out[t] = (sel.selected.fit.terms[t], True)
        elif sel.full.mask[i] > 0:
            out[t] = (TermEstimate(0.0, 0.0, float(full_hi[i]), UNITS[t]), False)
    return out
