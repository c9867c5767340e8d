"""Five-term Allan noise fits with intervals: the paper's least squares and GLS.

:func:`fit_paper_lsq`: paper 002, s2(tau) = sum_n a_n tau^n, a_n >= 0, relative weights,
:func:`fogbayes.allan.model.params_from_coefficients`; sandwich covariance with
Var s2hat = 2 s2^2 / nu. :func:`fit_wls`: GLS in theta = log(Q, N, B, K, R),
r_j = log s2hat_j - log s2_j(theta) - (psi(nu_j/2) - log(nu_j/2)), V from trigamma variances and
:mod:`fogbayes.stats.allan_cov`, reweighted (:func:`_reweighted`), penalty sd 10; intervals
exp(theta +- 1.645 se), lower bound 0 when dropping the term costs < 2.71 in chi-square.
Units: :mod:`fogbayes.allan.model`; slopes: :mod:`fogbayes.allan.readout`.
"""

from __future__ import annotations

from typing import NamedTuple

import math

import numpy as np
from scipy import optimize

from .model import (
    _A_PER_P2, POWERS, TERMS, UNITS, AllanParams, params_from_coefficients,
)
from ..support.tails import chi2_ppf, chi2_sf, norm_ppf
from .data import AllanFitData, log_moments, model_moments, restrict

Z90 = float(norm_ppf(0.95))
CHI2_90 = float(chi2_ppf(0.9, 1))
GOF_LEVEL = 1e-3
PENALTY_SD = 10.0
_STEPS = 200
MAX_PASSES = 12
#: largest change of a log-parameter between passes at which the weights count as settled
SETTLED_STEP = 1e-3


class TermEstimate(NamedTuple):
    """One noise coefficient with its 90 % interval, canonical unit."""

    value: float
    low: float
    high: float
    unit: str


class AllanFit(NamedTuple):
    """A five-term fit: per-term estimates, point parameters, convergence and extras."""

    method: str
    terms: dict
    params: AllanParams
    converged: bool
    info: dict


def _estimates(values, lows, highs, mask) -> dict:
    return {t: TermEstimate(float(v), float(lo), float(hi), UNITS[t])
            for t, v, lo, hi, on in zip(TERMS, values, lows, highs, mask) if on}


def _mask(terms) -> np.ndarray:
    return np.array([t in terms for t in TERMS], dtype=float)


# -- paper 002 ---------------------------------------------------------------------------
def fit_paper_lsq(data: AllanFitData, terms=TERMS) -> AllanFit:
    """Paper 002's least-squares fit (non-negative, relative weights) and its conversions."""
    mask = _mask(terms)
    X = np.stack([data.tau ** POWERS[t] for t in TERMS], axis=1) * mask
    w = 1.0 / data.avar  # relative residuals
    a, _ = optimize.nnls(X * w[:, None], np.ones_like(data.avar))
    # sandwich covariance of a (weights are not the inverse variances)
    var_obs = 2.0 * data.avar**2 / data.edf
    on = mask > 0
    Xw = (X * w[:, None])[:, on]
    bread = np.linalg.pinv(Xw.T @ Xw)
    meat = Xw.T @ (Xw * (w**2 * var_obs)[:, None])
    se = np.zeros(5)
    se[on] = np.sqrt(np.clip(np.diag(bread @ meat @ bread), 0, None))
    coef = lambda aa: params_from_coefficients(np.sqrt(np.clip(aa, 0, None)))  # noqa: E731
    value, low, high = coef(a), coef(a - Z90 * se), coef(a + Z90 * se)
    resid = X @ a / data.avar - 1
    return AllanFit("paper-lsq", _estimates(value, low, high, mask), value, True,
                    {"C": np.sqrt(a), "a": a, "rms_relative_residual": float(np.sqrt(np.mean(resid**2)))})


# -- GLS in log space (NumPy, SciPy's trust-region least squares) ---------------------------
_POWERS = np.array([POWERS[t] for t in TERMS], dtype=float)
_A = np.array([_A_PER_P2[t] for t in TERMS])


def _log_model(logp, mask, tau):
    """log sigma^2(tau) of the five-term model at log-parameters ``logp`` (terms in ``mask``);
    -inf for a model with no term (the chi-square "without" the only term is then inf)."""
    with np.errstate(divide="ignore"):
        return np.log(_term_parts(logp, mask, tau).sum(axis=0))


def _term_parts(logp, mask, tau):
    return (_A * np.exp(2.0 * np.asarray(logp)) * mask)[:, None] * \
        np.asarray(tau)[None, :] ** _POWERS[:, None]


def _log_model_jacobian(logp, mask, tau):
    """d log sigma^2(tau_j) / d logp_i = 2 a_i p_i^2 tau_j^n_i / sigma^2(tau_j), (K, 5)."""
    parts = _term_parts(logp, mask, tau)
    return (2.0 * parts / parts.sum(axis=0)).T


def _whitener(prec):
    """W with W^T W = prec (prec symmetric positive semi-definite: zero rows allowed)."""
    vals, vecs = np.linalg.eigh(0.5 * (prec + prec.T))
    return (vecs * np.sqrt(np.clip(vals, 0.0, None))).T


def _minimise(logp0, mask, tau, target, prec, loc):
    """argmin 1/2 r' P r + 1/2 sum_on ((logp - loc) / sd)^2, r = target - log model:
    Gauss-Newton with a trust region (``scipy.optimize.least_squares``) on the whitened
    residuals, only the terms in ``mask`` free. Returns (logp, loss, gradient norm)."""
    on = np.asarray(mask) > 0
    W = _whitener(np.asarray(prec))
    x = np.array(logp0, dtype=float)

    def full(v):
        y = x.copy()
        y[on] = v
        return y

    def resid(v):
        lp = full(v)
        return np.concatenate([W @ (target - _log_model(lp, mask, tau)),
                               (v - loc[on]) / PENALTY_SD])

    def jac(v):
        J = _log_model_jacobian(full(v), mask, tau)[:, on]
        return np.vstack([-W @ J, np.eye(int(on.sum())) / PENALTY_SD])

    if not on.any():
        return x, 0.0, 0.0
    sol = optimize.least_squares(resid, x[on], jac=jac, method="trf", xtol=1e-12,
                                 ftol=1e-12, gtol=1e-10, max_nfev=_STEPS)
    return full(sol.x), float(sol.cost), float(np.linalg.norm(sol.grad))


def _gls_weights(logp, mask, data, keep):
    """Target offset b and precision of the log estimates at the current parameters; taus
    outside ``keep`` get zero rows and columns (the precision of the kept ones' marginal)."""
    _, nu, corr = model_moments(np.asarray(logp, float), np.asarray(mask, float), data)
    b, v = log_moments(nu)
    sd = np.sqrt(v)
    cov = corr * np.outer(sd, sd)
    prec = np.zeros_like(cov)
    prec[np.ix_(keep, keep)] = np.linalg.inv(cov[np.ix_(keep, keep)])
    return np.asarray(b), prec


def initial_logp(data: AllanFitData, mask) -> np.ndarray:
    """Start values: the paper's fit, with terms it sets to 0 put 4 e-folds below their scale."""
    p = np.array(fit_paper_lsq(data).params)
    start = data.prior_loc - 4.0
    logp = np.log(np.maximum(p, 1e-300))
    return np.where((p > 0) & (logp > start), logp, start) * (mask > 0) + data.prior_loc * (mask == 0)


def upper_caps(data: AllanFitData, keep) -> np.ndarray:
    """Largest value of each term that stays below every kept AVAR estimate's one-sided
    99.9 % upper bound on its own: no interval needs to reach beyond it (it only stops the
    log-space bounds of unresolved terms at absurd values)."""
    hi = data.edf * data.avar / chi2_ppf(0.001, data.edf)
    return np.array([np.min(np.sqrt(hi[keep] / (_A_PER_P2[t] * data.tau[keep] ** POWERS[t])))
                     for t in TERMS])


def fit_wls(data: AllanFitData, terms=TERMS, *, keep=None, passes: int = 3) -> AllanFit:
    """GLS fit in log-parameter space with the EDF-based covariance (see module docstring).

    ``keep`` (boolean, per tau) restricts the fit to some taus. ``info["gof_p"]`` is the
    chi-square goodness of fit (kept taus - active terms degrees of freedom); when it is below
    GOF_LEVEL the model does not describe the data to within their noise and the standard
    errors are scaled by sqrt(chi2 / dof) (``info["dispersion"]``). Upper bounds are capped by
    :func:`upper_caps`.
    """
    mask = _mask(terms)
    keep = np.ones(data.tau.size, bool) if keep is None else np.asarray(keep, bool)
    logp = initial_logp(data, mask)
    tau, loc = np.asarray(data.tau, float), np.asarray(data.prior_loc, float)
    log_obs = np.log(data.avar)
    logp, loss, gnorm, b, prec, settled, n_passes = _reweighted(
        logp, mask, data, keep, log_obs, passes)
    on = mask > 0
    cov = _gauss_newton_cov(logp, mask, tau, prec)
    se = np.sqrt(np.diag(cov))
    value = np.exp(logp) * mask
    converged = bool(np.isfinite(loss) and gnorm < 1e-4 * max(1.0, abs(loss)))
    target = log_obs - b
    chi2 = _chi2(logp, mask, tau, target, prec)
    # Profile-likelihood lower bound: a term whose removal raises chi2 by less than the 90 %
    # point of chi2_1 (2.71) is compatible with 0, and a log-space interval cannot say so.
    d_chi2 = np.full(5, np.inf)
    for i in np.flatnonzero(on):
        sub = mask.copy()
        sub[i] = 0.0
        x, _, _ = _minimise(logp, sub, tau, target, prec, loc)
        d_chi2[i] = _chi2(x, sub, tau, target, prec) - chi2
    dof = max(1, int(keep.sum() - on.sum()))
    gof_p = float(chi2_sf(chi2, dof))
    dispersion = max(1.0, chi2 / dof) if gof_p < GOF_LEVEL else 1.0
    half = Z90 * se * np.sqrt(dispersion)  # quasi-likelihood: a misfit widens every interval
    low = np.where(d_chi2 < CHI2_90 * dispersion, 0.0, np.exp(logp - half))
    # the cap stops absurd upper bounds, never below the estimate itself (a misfit record,
    # e.g. a sine, can put the estimate above the cap: the interval must still hold it)
    high = np.exp(np.minimum(logp + half, np.maximum(np.log(upper_caps(data, keep)), logp)))
    return AllanFit("wls", _estimates(value, low, high, mask), AllanParams(*value), converged,
                    {"logp": logp, "se_log": se * np.sqrt(dispersion),
                     "cov_log": cov * dispersion, "chi2": chi2, "dof": dof,
                     "gof_p": gof_p, "dispersion": dispersion, "keep": keep,
                     "d_chi2_without": dict(zip(TERMS, d_chi2)), "loss": loss,
                     "gradient_norm": gnorm, "weights_settled": settled,
                     "passes": n_passes})


def _gauss_newton_cov(logp, mask, tau, prec) -> np.ndarray:
    """(J^T V^-1 J + I / PENALTY_SD^2)^-1 on the terms in ``mask`` (zeros elsewhere), (5, 5)."""
    on = np.asarray(mask) > 0
    J = _log_model_jacobian(logp, mask, tau)[:, on]
    cov = np.zeros((5, 5))
    cov[np.ix_(on, on)] = np.linalg.inv(J.T @ prec @ J + np.eye(int(on.sum())) / PENALTY_SD**2)
    return cov


def log_covariance_at(fit: AllanFit, data: AllanFitData, logp) -> np.ndarray:
    r"""The covariance of ``fit``'s log-parameters with the GLS weights and the Jacobian taken
    at other log-parameters ``logp`` (same terms, same kept taus, same dispersion).

    The Gauss-Newton covariance depends on where it is evaluated: at the unit's own estimate
    a term estimated high also dominates more taus and so gets a smaller log-space variance.
    Across units those variances follow the errors (correlation +0.37 for B on the fleets of
    ``benchmarks/bench_pool.py``), and a precision-weighted mean leans towards the high side.
    Evaluated at a better guess of the truth (a pooled, shrunk estimate) they do not.
    ``data`` is the data the fit used (as :func:`fit_range` returns it).
    """
    mask = _mask(fit.terms)
    keep = np.asarray(fit.info["keep"], bool)
    if keep.size != data.tau.size:  # fit_range's data are already restricted to keep
        keep = np.ones(data.tau.size, bool)
    _, prec = _gls_weights(np.asarray(logp, float), mask, data, keep)
    return _gauss_newton_cov(logp, mask, np.asarray(data.tau, float), prec) * fit.info["dispersion"]


def _reweighted(logp, mask, data, keep, log_obs, passes):
    r"""Iterated GLS: minimise under the weights at the current estimate, recompute them there.

    ``passes`` passes as a rule, more (up to MAX_PASSES) while the estimate still moves: the
    weights depend on the parameters and the iteration can cycle when two terms trade off
    (K-dominated and R-dominated solutions alternating on a record whose longest taus fall
    low; 18 of 100 simulated 3.6 h five-term records never settled). If it does not settle,
    the pass end with the smallest Gaussian negative log-likelihood of the log-AVAR
    estimates, :math:`r^\top V^{-1} r + \log\det V` (+ the penalty), each under its *own*
    weights, is kept. Before, a cycle ended on whichever solution the pass count fell on:
    a simulated five-term record got chi2 63 on 11 dof (gof p 2e-9, so every interval was
    widened 2.4x), K at 0.54x its truth and a spurious R, where the cycle's other solution
    has chi2 13.8 and K at 1.04x.
    Returns the estimate, its minimiser's loss and gradient norm, the weights (b, prec) at
    the estimate, whether the iteration settled, and the number of passes made.
    """
    tau, loc = np.asarray(data.tau, float), np.asarray(data.prior_loc, float)
    on = np.asarray(mask) > 0
    b, prec = _gls_weights(logp, mask, data, keep)
    ends = []  # (negative log-likelihood, logp, loss, gnorm, b, prec) of each pass end
    for n in range(1, MAX_PASSES + 1):
        new, loss, gnorm = _minimise(logp, mask, tau, log_obs - b, prec, loc)
        step = float(np.max(np.abs(new - logp)[on], initial=0.0))
        logp = new
        b, prec = _gls_weights(logp, mask, data, keep)
        if n >= passes and step < SETTLED_STEP:
            return logp, loss, gnorm, b, prec, True, n
        ends.append((_own_negloglik(logp, mask, tau, log_obs - b, prec, loc, keep),
                     logp, loss, gnorm, b, prec))
    _, logp, loss, gnorm, b, prec = min(ends, key=lambda e: e[0])
    return logp, loss, gnorm, b, prec, False, MAX_PASSES


def _own_negloglik(logp, mask, tau, target, prec, loc, keep) -> float:
    """-2 log L (up to a constant) of the kept log-AVAR estimates under the weights at
    ``logp`` itself: chi2 + log det V, with the weak penalty of :func:`_minimise`."""
    on = np.asarray(mask) > 0
    _, logdet_prec = np.linalg.slogdet(prec[np.ix_(keep, keep)])
    penalty = float(np.sum(((np.asarray(logp) - loc)[on] / PENALTY_SD) ** 2))
    return _chi2(logp, mask, tau, target, prec) - logdet_prec + penalty


def _chi2(logp, mask, tau, target, prec) -> float:
    model = _log_model(logp, mask, tau)
    if not np.all(np.isfinite(model)):  # no term left: nothing is fitted
        return math.inf
    r = np.asarray(target) - model
    return float(r @ prec @ r)


def fit_range(data: AllanFitData, terms=TERMS, *, max_drop_fraction: float = 1 / 3,
              min_taus: int = 7) -> tuple[AllanFitData, AllanFit, int]:
    """Leave out the shortest taus while the GLS fit fails its goodness-of-fit test.

    Real sensors filter and decimate: their first octaves often follow no noise term (the
    ADIS16405's ADEV is flat from 0.01 to 0.02 s). Starting from all octave taus, the
    shortest one is left out and the fit repeated while ``gof_p < GOF_LEVEL``, at most
    ``max_drop_fraction`` of them and keeping ``min_taus``. Returns the data used (restricted),
    its GLS fit and the number of taus left out. On data that follow the model this leaves
    out nothing in all but ~GOF_LEVEL of records.
    """
    keep = np.ones(data.tau.size, bool)
    fit, dropped = fit_wls(data, terms), 0
    limit = min(int(max_drop_fraction * data.tau.size), data.tau.size - min_taus)
    while fit.info["gof_p"] < GOF_LEVEL and dropped < limit:
        dropped += 1
        keep[:dropped] = False
        fit = fit_wls(data, terms, keep=keep)
    return restrict(data, keep), fit, dropped
