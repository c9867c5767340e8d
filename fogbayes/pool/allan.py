"""Pooled five-term Allan noise of several runs or units: population, spread, outliers.

Per unit, y_u = log theta_u and Sigma_u from :func:`fogbayes.allan.fit.fit_range`; the pooled
terms (default N, B, K) follow :mod:`fogbayes.pool.normal`. Unresolved terms are conditioned on
(:func:`resolved_covariance`) or enter by their likelihood in the variance coefficient
(:func:`censored_covariance`); a second pass takes Sigma_u at the population median
(:func:`at_population`). Per term (90 %): median e^mu, spread s, a new unit's range, each unit
unpooled and shrunk, outlier p-values; a term the population does not resolve
(:func:`absence_chi2`) is an upper bound only (``"resolved": false``).
"""

from __future__ import annotations

import math
from typing import NamedTuple, Sequence

import numpy as np

from ..allan.fit import CHI2_90, GOF_LEVEL
from ..allan.model import TERMS, UNITS

SCHEMA = "fogbayes.pool/1"
DEFAULT_TERMS = ("N", "B", "K")
CI = 0.9
#: a unit is flagged when its outlier p-value is below this. 0.02 spends under half of a 5 %
#: false-flag budget (measured 1.2 % of clean units at 0.02, 0.45 % at 0.01, on 100 fleets of
#: benchmarks/bench_pool.py) for detection (a unit with one term 5x its own: 94 % against 90 %).
#: Held out (fleets 100-179, not used to choose it): 92.5 % detected, 1.44 % false flags.
FLAG_LEVEL = 0.02


class UnitFit(NamedTuple):
    """One unit's single-record GLS fit, what the pool needs of it."""

    name: str
    source: str | None
    n: int
    fs: float
    logp: np.ndarray        # (5,) log canonical parameters
    cov: np.ndarray         # (5, 5) their covariance
    terms: dict             # term -> TermEstimate (90 %, low = 0 when not resolved)
    taus_left_out: int
    gof_p: float
    converged: bool
    data: object = None     # the AllanFitData the fit used (None: no re-evaluation)
    fit: object = None      # its AllanFit


def fit_unit(rec, *, name: str | None = None) -> UnitFit:
    """The GLS five-term fit of one recording (as ``fogbayes allan`` makes it)."""
    from ..allan.data import prepare
    from ..allan.fit import fit_range
    from ..allan.workflow import uniform_rate

    y, fs, _ = uniform_rate(rec)
    finite = y[np.isfinite(y)]
    if finite.size == 0 or np.ptp(finite) == 0:
        from ..allan.workflow import AllanInputError

        raise AllanInputError("the output is constant: its Allan variance is zero at every "
                              "tau and there is no noise to pool", file=rec.meta.source,
                              column="output", fix="check the column (a stuck or disconnected "
                              "sensor?), or leave this recording out of the pool")
    data, fit, left_out = fit_range(prepare(y, fs))
    return unit_from_fit(name or rec.meta.sensor_id, rec.meta.source, int(y.size), fs, data,
                         fit, left_out)


def unit_from_fit(name, source, n, fs, data, fit, left_out) -> UnitFit:
    """A :class:`UnitFit` of a :func:`fogbayes.allan.fit.fit_range` result."""
    return UnitFit(name, source, n, fs, np.asarray(fit.info["logp"]),
                   np.asarray(fit.info["cov_log"]), dict(fit.terms), left_out,
                   float(fit.info["gof_p"]), bool(fit.converged), data, fit)


def at_population(units: Sequence[UnitFit], terms: Sequence[str], median: dict) -> list[UnitFit]:
    r"""The units with their covariance re-evaluated where the population puts them.

    A unit's GLS covariance is evaluated at its own estimate, where a term estimated high
    dominates more taus and gets a smaller log-space variance: across a fleet the weights
    follow the errors, and the precision-weighted population median leans high (B by
    +0.014 in log, se 0.0012, on the 200 fleets of ``benchmarks/bench_pool.py``; the plain
    mean of the units is unbiased). Under the population model the unit's sampling
    covariance is that at its true parameters, which the population median estimates
    without that correlation; so each pooled term is set to the population ``median``
    (the unit's other terms stay at its estimate) and the covariance is taken there
    (:func:`fogbayes.allan.fit.log_covariance_at`; same kept taus, same dispersion). Where a
    unit is taken alone -- its outlier test and its shrunk draws given the population --
    it keeps its own covariance: a unit far from the population is better described
    there. Taken at the population median, a unit with 5x the K got a wider K and was
    flagged in 31 of 40 fleets instead of 35 (level 0.02), and the units' errors over
    their sds had RMS N 0.97, B 1.23, K 0.83 against 0.95, 1.01, 1.04 at their own
    estimates (200 units, ``benchmarks/pool_allan_units.py``; ``benchmarks/RESULTS_pool.md``). Units
    without their fit's data are returned unchanged.
    Only the terms in ``terms`` (those the population resolves) are moved.
    """
    from ..allan.fit import log_covariance_at

    out = []
    for u in units:
        if u.data is None or u.fit is None:
            out.append(u)
            continue
        at = np.array(u.logp, dtype=float)
        for t in terms:
            at[TERMS.index(t)] = np.log(median[t])
        out.append(u._replace(cov=log_covariance_at(u.fit, u.data, at)))
    return out


def resolved_covariance(unit: UnitFit) -> np.ndarray:
    r"""The unit's five-term log-space covariance, conditioned on its unresolved terms.

    A term whose 90 % interval reaches 0 has no meaningful log-space variance: its log is
    unbounded below, and the Gauss-Newton covariance spreads that width over the terms it
    is correlated with (N with Q at the shortest taus: correlation about -0.95). Taking
    the resolved terms' marginal therefore overstates them: on the simulated fleets of
    ``benchmarks/bench_pool.py`` two of 200 units had N's log sd at 0.14 and 0.22 while
    their N was off by 0.003 and 0.034, and pooling pulled them towards the population
    (``benchmarks/pool_allan_units.py``). So the resolved terms r are taken given the
    unresolved terms c at their estimates,

    .. math:: \Sigma_{rr} - \Sigma_{rc} \Sigma_{cc}^{-1} \Sigma_{cr},

    and each unresolved term keeps its own variance with no covariance (the pool replaces
    a pooled one's by its flat-below width). Over the resolved terms of those 200 units the
    errors over the conditioned sds have RMS 1.04 (N), 1.00 (B), 1.04 (K): still calibrated.
    (Those two units' wide N came from single-unit fits stopped on the wrong side of a GLS
    cycle, :func:`fogbayes.allan.fit._reweighted`; the conditioning stays right for any
    unit whose terms are unresolved.)
    """
    cov = np.asarray(unit.cov, dtype=float)
    cen = np.array([t in unit.terms and unit.terms[t].low <= 0.0 for t in TERMS])
    if not cen.any():
        return cov.copy()
    out = np.diag(np.diag(cov))
    r = ~cen
    if r.any():
        crc = cov[np.ix_(r, cen)]
        inv_cc = np.linalg.pinv(cov[np.ix_(cen, cen)], hermitian=True)
        cond = cov[np.ix_(r, r)] - crc @ inv_cc @ crc.T
        out[np.ix_(r, r)] = 0.5 * (cond + cond.T)
    return out


def profile_gains(unit: UnitFit) -> np.ndarray:
    """(5,) the chi-square the unit's GLS fit gains by each term, the others refitted
    (``d_chi2_without`` over the dispersion; 0 where negative: a term the fit does not
    need), the profile likelihood of the term at 0. Infinite for a term the unit resolves
    without that record; 0 for an unresolved one."""
    gain = None if unit.fit is None else unit.fit.info.get("d_chi2_without")
    if gain is None:
        return np.array([math.inf if t in unit.terms and unit.terms[t].low > 0 else 0.0
                         for t in TERMS])
    disp = float(unit.fit.info.get("dispersion", 1.0))
    return np.array([max(float(gain[t]), 0.0) / disp if t in gain else 0.0 for t in TERMS])


def _plateau_drop(log_s, v_hat, var_v):
    """x(0)^2 / var_x with x = log(1 + (v - v_hat) / S), var_x = var_v / S^2."""
    S = np.exp(log_s)
    return S**2 * np.log1p(-v_hat / S) ** 2 / var_v


def censored_covariance(unit: UnitFit) -> tuple[np.ndarray, np.ndarray]:
    r"""The likelihood the pool gives the terms a unit does not resolve
    (:func:`fogbayes.pool.normal.unit_log_lik`): (5,) ceilings :math:`c_t` and the (5, 5)
    covariance of the shifts :math:`x_t = \log(1 + (v_t - \hat v_t) / S_t)`,
    :math:`v_t = p_t^2`, :math:`S_t = e^{2 c_t}`.

    Near the estimate :math:`x_t \approx (v_t - \hat v_t) / S_t`: normal in :math:`v`, the
    parameter the AVAR is linear in, so the Gauss-Newton covariance is taken there,
    :math:`C_v = (J_v^\top V^{-1} J_v)^{-1}`, :math:`J_{v,jt} = \partial
    \log\sigma^2(\tau_j) / \partial v_t = a_t \tau_j^{n_t} / \sigma^2(\tau_j)`, with the GLS
    weights at the unit's estimate, over all the terms it fits (a block of it is the
    marginal of those terms), without the log-space penalty (which only keeps an absent
    term's log finite), times the fit's dispersion; :math:`C_x = C_v / (S S^\top)`. It keeps
    the terms' correlation: at 1 h B and K trade off (correlation about -0.75), so the
    records exclude both being 0 more firmly than either.

    As :math:`v_t \to 0` the likelihood levels off at :math:`x_t(0)^2 / C_{x,tt}`;
    :math:`S_t` is chosen so that this is the chi-square the unit's fit gains by the term
    (:func:`profile_gains`, the others refitted), which the linear approximation alone
    (:math:`\hat v^2 / C_{v,tt}`, the limit :math:`S \to \infty`) understates by up to 1.5 on
    the 1 h units of benchmarks/RESULTS_pool.md. Far above the estimate :math:`x_t` grows
    as :math:`\log v_t`, as a log-AVAR residual does: the likelihood falls off as a
    log-normal, not as a normal in :math:`v`. Where the linear drop already exceeds the
    profile one, :math:`S_t` is 1000 times the value at which the term alone would make
    the measured AVAR where it is most visible (``prior_loc``). A unit without its fit's
    data: ceilings at its upper bounds and its log-space covariance carried to :math:`x`
    (:math:`dx = 2 (\hat v / S)\, d\log p`)."""
    from scipy.optimize import brentq

    from ..allan.fit import _A, _POWERS, _gls_weights, _mask, _term_parts
    from .normal import _MIN_REST

    cov = np.asarray(unit.cov, dtype=float)
    logp = np.asarray(unit.logp, dtype=float)
    if unit.data is None or unit.fit is None:
        ceil = np.array([np.log(unit.terms[t].high) if t in unit.terms else logp[i] + 1.0
                         for i, t in enumerate(TERMS)])
        r = 2.0 * np.exp(2.0 * (logp - ceil))
        return ceil, cov * np.outer(r, r)
    mask = _mask(unit.terms)
    on = mask > 0
    data = unit.data
    tau = np.asarray(data.tau, dtype=float)
    _, prec = _gls_weights(logp, mask, data, np.ones(tau.size, bool))
    total = _term_parts(logp, mask, tau).sum(axis=0)
    scale = np.exp(2.0 * np.asarray(data.prior_loc, dtype=float))  # columns of order 1
    J = ((_A * scale)[None, :] * tau[:, None] ** _POWERS[None, :] / total[:, None])[:, on]
    cov_v = np.zeros((5, 5))
    cov_v[np.ix_(on, on)] = (np.linalg.pinv(J.T @ prec @ J, hermitian=True)
                             * float(unit.fit.info["dispersion"])) * np.outer(scale[on], scale[on])
    v_hat = np.exp(2.0 * logp)
    gains = profile_gains(unit)
    log_s = np.log(scale * 1e3)
    for i in np.flatnonzero(on):
        var_v = max(cov_v[i, i], 1e-300)
        lo = np.log(v_hat[i] / (1.0 - _MIN_REST))
        hi = max(log_s[i], lo + 1.0)
        target = max(gains[i], 1e-6)
        if _plateau_drop(hi, v_hat[i], var_v) < target <= _plateau_drop(lo, v_hat[i], var_v):
            log_s[i] = brentq(lambda q: _plateau_drop(q, v_hat[i], var_v) - target, lo, hi,
                              xtol=1e-6)
        else:
            log_s[i] = hi
    S = np.exp(log_s)
    return 0.5 * log_s, cov_v / np.outer(S, S)


def absence_chi2(units: Sequence[UnitFit], terms: Sequence[str]) -> dict:
    r"""Per pooled term, how firmly the units' records together exclude its absence: the
    likelihood-ratio chi-square of one value :math:`v` common to all units against
    :math:`v = 0` in all, each unit's profile likelihood normal in :math:`v` about its
    estimate :math:`\hat v_u` and falling by its fit's gain :math:`g_u` at 0
    (:func:`profile_gains`: the single-unit test of the term, made across the units),

    .. math:: \chi^2 = \Big(\sum_u g_u / \hat v_u\Big)^2 \Big/ \sum_u g_u / \hat v_u^2 .

    Infinite where a unit resolves the term alone. The population resolves the term when
    this is at least the 90 % point of :math:`\chi^2_1` (2.71), the single-unit rule (a
    spread between units would only raise it: the rule errs towards a bound); otherwise the
    records are compatible with the term being absent in every unit, and the pool states an
    upper bound only, whatever the prior makes of the region they cannot see."""
    out = {}
    for t in terms:
        i = TERMS.index(t)
        if any(u.terms[t].low > 0.0 for u in units):
            out[t] = math.inf
            continue
        g = np.array([profile_gains(u)[i] for u in units])
        v = np.exp(2.0 * np.array([float(u.logp[i]) for u in units]))
        den = float(np.sum(g / v**2))
        out[t] = float(np.sum(g / v) ** 2 / den) if den > 0 else 0.0
    return out


#: the level of the upper bound stated for an unresolved term
UPPER_LEVEL = 0.5 + CI / 2


def amplitude_scales(units: Sequence[UnitFit], terms: Sequence[str]) -> np.ndarray:
    r"""(P,) the scale A of each pooled term's prior, population median ~ HalfCauchy(0, A).

    A noise term is an amplitude (the AVAR holds its square): its prior is put on the
    amplitude, as for a scale in a hierarchical model (Gelman 2006), not on its log. A
    log-uniform or wide log-normal prior puts as much mass on each decade far below what
    the records can see as on the decade the units measure; where the units do not resolve
    the term the likelihood is level there, and the posterior followed the prior down to
    :math:`10^{-10}` (four 1 h units: B [7.7e-11, 0.0096] deg/h with truth 0.02). The
    half-Cauchy is flat below A and falls as :math:`m^{-2}` above. A is the largest over
    the units of the value at which the term alone would make the unit's measured AVAR
    where the term is most visible (``prior_loc`` of :mod:`fogbayes.allan.data`): no record
    holds more of the term, so the prior is about flat over every value the data allow.
    Units without their fit's data: the largest of their upper bounds."""
    out = []
    for t in terms:
        i = TERMS.index(t)
        out.append(max(float(np.exp(u.data.prior_loc[i])) if u.data is not None
                       else u.terms[t].high for u in units))
    return np.array(out)


def _upper(draws_log: np.ndarray, unit: str) -> dict:
    return {"upper": float(np.exp(np.quantile(draws_log, UPPER_LEVEL))), "level": UPPER_LEVEL,
            "unit": unit}


def _interval(draws_log: np.ndarray, unit: str) -> dict:
    lo, med, hi = np.exp(np.quantile(draws_log, [0.5 - CI / 2, 0.5, 0.5 + CI / 2]))
    return {"value": float(med), "low": float(lo), "high": float(hi), "unit": unit}


def _spread(s: np.ndarray) -> dict:
    lo, med, hi = np.quantile(s, [0.5 - CI / 2, 0.5, 0.5 + CI / 2])
    return {"log_sd": {"value": float(med), "low": float(lo), "high": float(hi)},
            "factor": {"value": float(np.exp(med)), "low": float(np.exp(lo)),
                       "high": float(np.exp(hi))}}


def check_units(units: Sequence[UnitFit], terms: Sequence[str]) -> list[str]:
    """Warnings the pool's reader must see: unresolved pooled terms, failed unit fits, mixed
    sample rates."""
    out = []
    for t in terms:
        missing = [u.name for u in units if u.terms[t].low <= 0.0]
        if missing:
            out.append(f"{t} is not resolved in {len(missing)} of {len(units)} units "
                       f"({', '.join(missing)}: their 90 % intervals reach 0): they enter "
                       f"with a likelihood that stays level towards {t} = 0, which the "
                       f"population's {t} rests on less; record longer to resolve it")
    failed = [u.name for u in units if not u.converged]
    if failed:
        out.append(f"the single-unit fit did not converge for {', '.join(failed)}")
    misfit = [f"{u.name} (p = {u.gof_p:.2g})" for u in units if u.gof_p < GOF_LEVEL]
    if misfit:
        out.append(f"the five-term model does not describe the Allan curve of "
                   f"{', '.join(misfit)}, even with its shortest taus left out: every interval "
                   f"of such a unit is widened by sqrt(chi2/dof), so it enters the pool with "
                   f"little weight; plot its ADEV (fogbayes allan --plot) before trusting it")
    rates = sorted({u.fs for u in units})
    if len(rates) > 1:
        out.append(f"the units were sampled at different rates ({', '.join(f'{r:g}' for r in rates)} "
                   "Hz): N, B, K are rate-independent, Q is not")
    return out


#: warm-up and draws per chain of the first pool (:func:`pool_allan`), whose medians place
#: the units' covariances (a smooth function of them) and whose adapted mass matrix and step
#: size the second pool keeps: two chains of 250 draws (ESS of mu ~120-250) put a median
#: within ~0.1 posterior sd. Its R-hat (up to 1.03 on four 1 h units) is not reported; the
#: second pool's is, and it met the convergence rule as often as after a first pool of 1000
#: warm-up steps and 1000 draws (benchmarks/RESULTS_pool.md)
FIRST_WARMUP, FIRST_SAMPLES = 500, 250


def pool_allan(units: Sequence[UnitFit], *, terms: Sequence[str] = DEFAULT_TERMS,
               seed: int = 0, flag_level: float = FLAG_LEVEL, prior=None,
               covariance_at: str = "population", outlier_test: str = "each",
               **sampler) -> dict:
    """Pool the units' five-term fits; a JSON-able document (module docstring).

    ``prior``: a datasheet prior (:mod:`fogbayes.inference.datasheet`; document, path or
    object): the population median of each pooled term the sheet gives is log-normal about
    the sheet value within its looseness; the others keep the weak default.
    ``covariance_at``: ``"population"`` pools twice, the second time with each unit's
    covariance taken at the first pool's population median (:func:`at_population`; units
    that carry their data); ``"estimate"`` once, with the covariances as the units' own fits
    give them. ``outlier_test``: ``"each"`` pooled term judged alone, or ``"joint"``
    (:func:`fogbayes.pool.normal.fit_pool`)."""
    from ..inference.datasheet import as_prior

    terms = tuple(t for t in TERMS if t in terms)
    prior = as_prior(prior)
    if covariance_at not in ("population", "estimate") or outlier_test not in ("each", "joint"):
        from ..errors import ArgumentError

        raise ArgumentError(f"covariance_at {covariance_at!r} / outlier_test {outlier_test!r}",
                            fix="covariance_at: 'population' or 'estimate'; outlier_test: "
                                "'each' or 'joint'")
    sampler = {**sampler, "outlier_test": outlier_test}
    first = None
    if covariance_at == "population" and any(u.data is not None for u in units):
        # the first pool serves only its medians and its adaptation: half the chains (on
        # two cores the time of one), FIRST_WARMUP and FIRST_SAMPLES
        first_sampler = {**sampler, "num_chains": max(1, sampler.get("num_chains", 4) // 2),
                         "num_warmup": sampler.get("num_warmup", FIRST_WARMUP),
                         "num_samples": min(FIRST_SAMPLES, sampler.get("num_samples", 1000))}
        first, _ = _pool(units, terms, seed, flag_level, prior, first_sampler, outliers=False)
        # only where the population resolves a term is its median a better place than the
        # unit's own estimate
        absence = absence_chi2(units, terms)
        median = {t: float(np.exp(np.median(first.mu[:, j]))) for j, t in enumerate(terms)
                  if absence[t] >= CHI2_90}
        own = _covariances(units, terms)
        units = at_population(units, tuple(median), median)
        # the same units and terms: the second pool keeps the first one's adaptation
        res, sheet = _pool(units, terms, seed, flag_level, prior,
                           {**sampler, "start": first.adaptation}, unit_cov=own)
    else:
        res, sheet = _pool(units, terms, seed, flag_level, prior, sampler)
    doc = _document(units, terms, res, sheet, prior, flag_level,
                    None if first is None else first.mu)
    doc["diagnostics"]["outlier_test"] = outlier_test
    return doc


def _covariances(units, terms) -> np.ndarray:
    """(U, P, P) the units' covariances of the pooled terms as the pool takes them."""
    idx = [TERMS.index(t) for t in terms]
    return np.stack([resolved_covariance(u)[np.ix_(idx, idx)] for u in units])


def _pool(units, terms, seed, flag_level, prior, sampler, outliers=True, unit_cov=None):
    """The arrays of the units' pooled terms and one :func:`fogbayes.pool.normal.fit_pool`.

    ``unit_cov``: the covariances taken where a unit is alone -- its outlier test and its
    shrunk draws (the units' own, :func:`pool_allan`); None: those of the model."""
    from .normal import MU_PRIOR_SD, fit_pool

    idx = [TERMS.index(t) for t in terms]
    y = np.stack([u.logp[idx] for u in units])
    cov = _covariances(units, terms)
    # a term a unit does not resolve: its likelihood is level towards 0 and log-quadratic
    # above, through the variance coefficient p^2 the AVAR is linear in (fogbayes.pool.normal)
    cens = np.array([[u.terms[t].low <= 0.0 for t in terms] for u in units], dtype=float)
    ceiling = y + 1.0
    for i, u in enumerate(units):
        c = np.flatnonzero(cens[i])
        if c.size:
            ceil, cx = censored_covariance(u)
            ceiling[i] = ceil[idx]
            cov[i][np.ix_(c, c)] = cx[np.ix_(np.array(idx)[c], np.array(idx)[c])]
    scale = amplitude_scales(units, terms)
    mu_prior, sheet = None, {}
    if prior is not None:
        sheet = {t: prior.terms[t] for t in terms if t in prior.terms}
        mu_prior = (np.array([np.log(sheet[t].value) if t in sheet else np.median(y[:, j])
                              for j, t in enumerate(terms)]),
                    np.array([sheet[t].sd_log if t in sheet else MU_PRIOR_SD for t in terms]))
        for j, t in enumerate(terms):  # the sheet's terms take its log-normal prior
            if t in sheet:
                scale[j] = np.nan
    res = fit_pool(y, cov, terms, censored=cens, ceiling=ceiling, seed=seed,
                   flag_level=flag_level,
                   mu_prior=mu_prior, amplitude_scale=scale, outliers=outliers,
                   unit_cov=unit_cov, **sampler)
    return res, sheet


def _document(units, terms, res, sheet, prior, flag_level, first_mu) -> dict:
    population = {}
    absence = absence_chi2(units, terms)
    seen = {}
    for j, t in enumerate(terms):
        seen[t] = absence[t] >= CHI2_90
        # JSON has no infinity: a term some unit resolves alone has no such chi-square
        evidence = {"chi2_absent": absence[t] if math.isfinite(absence[t]) else None,
                    "threshold": CHI2_90}
        if not seen[t]:  # an upper bound only: no median, spread or range to state
            population[t] = {"resolved": False, "median": _upper(res.mu[:, j], UNITS[t]),
                             "spread": None, "new_unit": _upper(res.new_unit[:, j], UNITS[t]),
                             "evidence": evidence}
            continue
        lo, hi = np.exp(np.quantile(res.new_unit[:, j], [0.5 - CI / 2, 0.5 + CI / 2]))
        population[t] = {"resolved": True, "median": _interval(res.mu[:, j], UNITS[t]),
                         "spread": _spread(res.spread[:, j]),
                         "new_unit": {"low": float(lo), "high": float(hi), "unit": UNITS[t]},
                         "evidence": evidence}
    rows = []
    for i, u in enumerate(units):
        per = {}
        for j, t in enumerate(terms):
            e = u.terms[t]
            alone = bool(e.low > 0)
            # a unit's pooled term is an interval where it or the population resolves it
            pooled = (_interval(res.units[:, i, j], UNITS[t]) if alone or seen[t]
                      else _upper(res.units[:, i, j], UNITS[t]))
            per[t] = {"single": {"value": e.value, "low": e.low, "high": e.high,
                                 "unit": e.unit, "resolved": alone},
                      "pooled": {**pooled, "resolved": alone or seen[t]}}
        p = float(res.outlier_p[i])
        rows.append({"name": u.name, "source": u.source, "n": u.n, "fs": u.fs,
                     "taus_left_out": u.taus_left_out, "gof_p": u.gof_p,
                     "converged": u.converged, "terms": per,
                     "outlier": {"p": p, "flagged": bool(p < flag_level),
                                 "method": res.diagnostics["loo_method"][i]}})
    diag = {k: v for k, v in res.diagnostics.items() if k != "loo_method"}
    reevaluated = first_mu is not None
    diag["covariance_at"] = "population median of a first pool" if reevaluated else \
        "each unit's own estimate"
    if reevaluated:
        diag["first_pool_median"] = {t: float(np.exp(np.median(first_mu[:, j])))
                                     for j, t in enumerate(terms) if seen[t]}
    flagged = [r["name"] for r in rows if r["outlier"]["flagged"]]
    return {"terms": list(terms), "ci": CI, "flag_level": flag_level,
            "population": population, "units": rows, "flagged": flagged,
            "warnings": check_units(units, terms), "diagnostics": diag,
            "converged": bool(diag["converged"]),
            "prior": None if prior is None else {
                **prior.record(), "rule": "log mu ~ N(log value, (ln looseness / 1.645)^2) "
                "for the population median of " + (", ".join(sheet) or "no pooled term")
                + "; the other pooled terms keep HalfCauchy(0, A) (population_prior)"},
            "population_prior": "each population median ~ HalfCauchy(0, A), A the largest "
                                "value of the term a unit's measured AVAR can hold"
                                + (" (the datasheet's terms: its log-normal)"
                                   if prior is not None else "")
                                + "; between-unit log sd ~ HalfNormal(1)",
            "method": "hierarchical normal model of the units' log-space GLS estimates "
                      "(fogbayes.pool.normal): NUTS on the population mean and spread, the "
                      "resolved unit parameters integrated out exactly and drawn given each "
                      "posterior draw; a term a unit does not resolve enters with its GLS "
                      "likelihood normal in the variance coefficient (the term squared), "
                      "jointly with its other unresolved terms, and is sampled; a term whose "
                      "absence in every unit the records do not exclude (evidence.chi2_absent "
                      "< 2.71) is stated as an upper bound only (resolved: false); outliers by "
                      "the leave-one-out posterior-predictive p-value of each pooled term "
                      "(two-sided; the smallest times their number), or of all jointly "
                      "(diagnostics.outlier_test)"}


def pool_document(pools: dict[str, dict], *, model: str = "allan") -> dict:
    """The document ``fogbayes pool`` writes: one pool per channel (axis or column)."""
    from .. import __version__

    return {"schema": SCHEMA, "model": model, "fogbayes_version": __version__,
            "channels": dict(pools)}
