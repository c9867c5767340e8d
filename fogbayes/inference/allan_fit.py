r"""Five-term Allan noise fits with intervals: the paper's least squares and GLS with optax.

* :func:`fit_paper_lsq` — paper 002's method: least squares of
  :math:`\hat\sigma^2(\tau) = \sum_n a_n \tau^n` (non-negative :math:`a_n = C_n^2`, relative
  weights so that every decade counts), converted with the paper's formulas
  (:func:`fogbayes.models.allan.params_from_coefficients`). Intervals: sandwich covariance of
  :math:`a_n` with :math:`\mathrm{Var}\,\hat\sigma^2 = 2\hat\sigma^4/\nu` (estimates taken as
  independent, as the paper does), 90 % normal bounds on :math:`a_n` clipped at 0.
* :func:`fit_wls` — generalised least squares in log-parameter space
  :math:`\theta = \log(Q, N, B, K, R)`:
  :math:`\min_\theta\ \tfrac12 r^\top V^{-1} r`, :math:`r_j = \log\hat\sigma^2_j -
  \log\sigma^2_j(\theta) - b_j`, with :math:`b_j = \psi(\nu_j/2) - \log(\nu_j/2)` the mean of
  :math:`\log(\chi^2_\nu/\nu)` and :math:`V` its covariance (trigamma variances, correlations of
  the estimates from :mod:`fogbayes.stats.allan_cov`), recomputed at the estimate for 3 passes;
  optax L-BFGS inside one ``lax.scan``. A weak normal penalty (sd 10 in log) keeps terms that
  are absent from running to zero. Intervals: :math:`\exp(\hat\theta \pm 1.645\,se)` with the
  Gauss-Newton covariance :math:`(J^\top V^{-1} J)^{-1}`; the lower bound is 0 when dropping
  the term raises the GLS chi-square by less than 2.71 (profile likelihood, 90 %).

Both return :class:`AllanFit` with values in the canonical units of
:mod:`fogbayes.models.allan`. The IEEE-952 slope readouts are in
:mod:`fogbayes.inference.allan_readout`.
"""

from __future__ import annotations

from functools import partial
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from scipy import optimize, stats

from ..models.allan import (
    _A_PER_P2, POWERS, TERMS, UNITS, AllanParams, params_from_coefficients,
)
from .allan_data import AllanFitData, log_moments, model_moments, restrict
from .lsq import lbfgs_scan

Z90 = float(stats.norm.ppf(0.95))
CHI2_90 = float(stats.chi2.ppf(0.9, 1))
GOF_LEVEL = 1e-3
_PENALTY_SD = 10.0
_STEPS = 200


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


# -- GLS in log space with optax ---------------------------------------------------------
def _log_model(logp, mask, tau):
    p2 = jnp.exp(2 * logp) * mask
    a = jnp.stack([_A_PER_P2[t] * p2[i] for i, t in enumerate(TERMS)])
    powers = jnp.array([POWERS[t] for t in TERMS], dtype=float)
    return jnp.log(jnp.sum(a[:, None] * tau[None, :] ** powers[:, None], axis=0))


def _loss(logp, mask, tau, target, prec, loc):
    r = target - _log_model(logp, mask, tau)
    pen = jnp.sum(mask * ((logp - loc) / _PENALTY_SD) ** 2)
    return 0.5 * r @ prec @ r + 0.5 * pen


@partial(jax.jit, static_argnames=("steps",))
def _minimise(logp0, mask, tau, target, prec, loc, steps: int = _STEPS):
    """L-BFGS in one lax.scan; returns the parameters, loss trace and final gradient norm."""
    fun = partial(_loss, mask=mask, tau=tau, target=target, prec=prec, loc=loc)
    x, trace = lbfgs_scan(fun, logp0, steps=steps)
    return x, trace, jnp.linalg.norm(jax.grad(fun)(x) * mask)


@jax.jit
def _log_weights(logp, mask, data: AllanFitData):
    """b, Var and correlation of the log estimates: one compiled program (run op by op,
    its ~60 small JAX operations compiled one program each, ~6 s of a CLI call)."""
    _, nu, corr = model_moments(logp, mask, data)
    b, v = log_moments(nu)
    return b, v, corr


def _gls_weights(logp, mask, data, keep):
    """Target offset b and precision of the log estimates at the current parameters; taus
    outside ``keep`` get zero rows and columns (the precision of the kept ones' marginal), so
    every subset has the same array shapes and the minimiser compiles once."""
    b, v, corr = _log_weights(jnp.asarray(logp), jnp.asarray(mask), data)
    sd = np.sqrt(np.asarray(v))
    cov = np.asarray(corr) * np.outer(sd, sd)
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
    hi = data.edf * data.avar / stats.chi2.ppf(0.001, data.edf)
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
    tau, loc = jnp.asarray(data.tau), jnp.asarray(data.prior_loc)
    log_obs = np.log(data.avar)
    for _ in range(passes):
        b, prec = _gls_weights(logp, mask, data, keep)
        x, trace, gnorm = _minimise(jnp.asarray(logp), jnp.asarray(mask), tau,
                                    jnp.asarray(log_obs - b), jnp.asarray(prec), loc)
        logp = np.asarray(x)
    b, prec = _gls_weights(logp, mask, data, keep)
    J = np.asarray(_log_model_jacobian(jnp.asarray(logp), jnp.asarray(mask), tau))
    on = mask > 0
    Jm = J[:, on]
    info_mat = Jm.T @ prec @ Jm + np.eye(int(on.sum())) / _PENALTY_SD**2
    se = np.zeros(5)
    se[on] = np.sqrt(np.diag(np.linalg.inv(info_mat)))
    value = np.exp(logp) * mask
    trace = np.asarray(trace)
    converged = bool(np.isfinite(trace[-1]) and float(gnorm) < 1e-4 * max(1.0, abs(trace[-1])))
    target = jnp.asarray(log_obs - b)
    chi2 = _chi2(logp, mask, tau, target, prec)
    # Profile-likelihood lower bound: a term whose removal raises chi2 by less than the 90 %
    # point of chi2_1 (2.71) is compatible with 0, and a log-space interval cannot say so.
    d_chi2 = np.full(5, np.inf)
    for i in np.flatnonzero(on):
        sub = mask.copy()
        sub[i] = 0.0
        x, _, _ = _minimise(jnp.asarray(logp), jnp.asarray(sub), tau, target, jnp.asarray(prec),
                            loc)
        d_chi2[i] = _chi2(np.asarray(x), sub, tau, target, prec) - chi2
    dof = max(1, int(keep.sum() - on.sum()))
    gof_p = float(stats.chi2.sf(chi2, dof))
    dispersion = max(1.0, chi2 / dof) if gof_p < GOF_LEVEL else 1.0
    half = Z90 * se * np.sqrt(dispersion)  # quasi-likelihood: a misfit widens every interval
    low = np.where(d_chi2 < CHI2_90 * dispersion, 0.0, np.exp(logp - half))
    high = np.exp(np.minimum(logp + half, np.log(upper_caps(data, keep))))
    return AllanFit("wls", _estimates(value, low, high, mask), AllanParams(*value), converged,
                    {"logp": logp, "se_log": se * np.sqrt(dispersion), "chi2": chi2, "dof": dof,
                     "gof_p": gof_p, "dispersion": dispersion, "keep": keep,
                     "d_chi2_without": dict(zip(TERMS, d_chi2)), "loss_trace": trace})


_log_model_jacobian = jax.jit(jax.jacfwd(lambda logp, mask, tau: _log_model(logp, mask, tau)))
_log_model_jit = jax.jit(lambda logp, mask, tau: _log_model(logp, mask, tau))


def _chi2(logp, mask, tau, target, prec) -> float:
    r = np.asarray(target) - np.asarray(_log_model_jit(jnp.asarray(logp), jnp.asarray(mask), tau))
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
