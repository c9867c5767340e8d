"""What the Allan noise fits see: octave AVAR estimates with their joint distribution.

Prepared once per record: the log-space moments of the estimates, the prior scale of each
term, and the covariance at given parameters (:mod:`fogbayes.stats.allan_cov`), shared by the
least-squares, GLS and Bayesian fits.
"""

from __future__ import annotations

from typing import NamedTuple

import math

import numpy as np

from ..support.xp import namespace, special

from ..errors import TooShortError
from .model import POWERS, TERMS, _A_PER_P2, avar, noise_scales
from ..stats.allan import allan_deviation
from ..stats.allan_cov import CovTensors, covariance_tensors, mixture_moments

MIN_TAUS = 6


class AllanFitData(NamedTuple):
    """Octave AVAR estimates of one record, in (deg/h)^2, and what their distribution needs."""

    tau: np.ndarray      # s
    avar: np.ndarray     # (deg/h)^2
    edf: np.ndarray      # Greenhall EDF from noise identification (for the first pass)
    counts: np.ndarray   # terms per estimate
    fs: float
    n: int
    tensors: CovTensors  # covariance of the estimates per unit noise scale
    prior_loc: np.ndarray  # (5,) log of each term's "largest plausible" value


def prepare(rate_deg_h, fs: float, *, m_max: int | None = None) -> AllanFitData:
    """Octave overlapping AVAR of ``rate_deg_h`` (NaN = gap) and its covariance tensors."""
    res = allan_deviation(rate_deg_h, fs, taus="octave", m_max=m_max)
    if res.tau.size < MIN_TAUS:
        raise TooShortError(
            f"the noise fit needs at least {MIN_TAUS} octave taus, the record gives "
            f"{res.tau.size} ({res.n} samples)", fix="record at least ~2^8 samples (longer is "
            "better: K and R need hours)")
    tensors = covariance_tensors(res.m, res.n_terms)
    return AllanFitData(res.tau, res.var, res.edf, res.n_terms, float(fs), res.n, tensors,
                        _prior_loc(res.tau, res.var))


def restrict(data: AllanFitData, keep) -> AllanFitData:
    """The same data on a subset of its taus (boolean or index ``keep``): the covariance
    tensors are per pair of taus, so slicing them is exact."""
    idx = np.arange(data.tau.size)[keep]
    t = data.tensors
    tensors = CovTensors(t.ms[idx], t.counts[idx], t.expect[:, idx], t.T[np.ix_(idx, idx)],
                         t.U[np.ix_(idx, idx)])
    return data._replace(tau=data.tau[idx], avar=data.avar[idx], edf=data.edf[idx],
                         counts=data.counts[idx], tensors=tensors,
                         prior_loc=_prior_loc(data.tau[idx], data.avar[idx]))


def _prior_loc(tau: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Log of the value at which each term alone would equal the measured AVAR where that term
    is most visible (shortest tau for Q and N, the minimum for B, longest tau for K and R)."""
    where = {"Q": 0, "N": 0, "B": int(np.argmin(v)), "K": -1, "R": -1}
    return np.array([0.5 * np.log(v[where[t]] / (_A_PER_P2[t] * tau[where[t]] ** POWERS[t]))
                     for t in TERMS])


def log_moments(nu):
    """Mean offset and variance of log(chi2_nu / nu): digamma(nu/2) - log(nu/2), trigamma."""
    xp = namespace(nu)
    sp = special(xp)
    return sp.digamma(nu / 2) - xp.log(nu / 2), sp.polygamma(1, nu / 2)


def cube_root_normal(obs, mean, nu):
    """Wilson-Hilferty: z = ((x)^(1/3) - (1 - 2/(9 nu))) / sqrt(2/(9 nu)), x = obs / mean, is
    ~N(0, 1) when obs ~ mean chi2_nu / nu; also returns log dz/dobs (the Jacobian)."""
    xp = namespace(obs, mean, nu)
    x = obs / mean
    v = 2.0 / (9.0 * nu)
    z = (xp.cbrt(x) - (1.0 - v)) / xp.sqrt(v)
    log_jac = -math.log(3.0) - (2.0 / 3.0) * xp.log(x) - 0.5 * xp.log(v) - xp.log(mean)
    return z, log_jac


def model_moments(logp, mask, data: AllanFitData, delta: float = 0.0):
    """Model mean AVAR, EDF and correlation of the estimates at log-parameters ``logp``.

    ``mask`` (5,) switches terms off; ``delta`` adds an independent log-normal model
    discrepancy of that standard deviation to each estimate (0 = the model is exact).

    Returns:
        ``(mean (K,), nu (K,), corr (K, K))``.
    """
    xp = namespace(logp, mask, delta)
    p = xp.exp(logp) * mask
    mean = avar(p, data.tau)
    ramp = p[4] / 3600.0 / data.fs  # R_s per sample: rate change between two samples
    mean_d, cov = mixture_moments(data.tensors, noise_scales(p, data.fs), ramp)
    counts = xp.asarray(data.counts, dtype=float)
    # relative covariance; the floor keeps the EDF below ~100 x the number of terms
    rel = cov / xp.outer(mean_d, mean_d) + xp.diag(2.0 / (100.0 * counts))
    var = xp.diag(rel)
    nu = 2.0 / (var + delta**2)  # Var(log estimate) ~ 2 / nu + delta^2
    corr = (rel + xp.eye(len(var)) * delta**2) / xp.sqrt(
        xp.outer(var + delta**2, var + delta**2))
    return mean, nu, corr
