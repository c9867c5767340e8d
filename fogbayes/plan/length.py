"""How long a static record must be to know one noise term to a given relative precision.

Octave m_k = 2^k with tau_k >= tau_min and m_k <= (n + 1) // 4; y_k = log s2hat(tau_k),
Cov y = V = D^(1/2) C D^(1/2), D = diag psi'(nu_k/2) (:func:`fogbayes.allan.data.model_moments`).
J_ki = 2 a_i p_i^2 tau_k^(n_i) / s2(tau_k), I(n) = J'V^-1 J + s_0^-2, se_i = sqrt((I^-1)_ii): the
GLS fit's standard error (:func:`fogbayes.allan.fit.fit_wls`). :func:`plan_length`: the shortest n
with sinh(z se_i(n)) <= ``precision``, on the grid n + 1 = (n_lo + 1) 2^(j/128). Assumes the model
is the noise and no gaps (check: benchmarks/RESULTS_plan.md).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from ..errors import FogbayesError
from ..allan.data import MIN_TAUS, AllanFitData, log_moments, model_moments
from ..allan.fit import PENALTY_SD  # the fit's own weak penalty: same se
from ..allan.model import TERMS, UNITS, AllanParams, avar, term_avar
from ..stats.allan_cov import covariance_tensors
from ..stats.allan_stencils import static_counts
from ..stats.taus import cluster_sizes
from ..support.tails import norm_ppf

#: Longest record a plan may ask for (days); beyond it the target is refused.
MAX_DAYS = 1000.0
#: Grid points per octave of record length searched (2^(1/128) - 1 = 0.54 % steps).
STEPS = 128


class PlanError(FogbayesError):
    """A recording-length plan that cannot be made as asked."""


class LengthPlan(NamedTuple):
    """The shortest record that knows ``term`` to ``precision`` (relative half-width)."""

    term: str
    precision: float       # target relative half-width (0.1 = +-10 %)
    level: float           # two-sided confidence of the interval
    n: int                 # samples
    fs: float              # Hz
    seconds: float
    hours: float
    se_log: float          # predicted se of log(term) at n
    half_width: float      # predicted relative half-width at n (<= precision)
    terms: tuple           # the model's terms
    params: AllanParams    # the values planned for
    tau_max: float         # longest octave tau of the planned record, s
    n_taus: int
    at_minimum: bool       # the shortest analysable record already meets the target


def z_value(level: float) -> float:
    """Two-sided normal quantile: 1.645 for 0.90."""
    return float(norm_ppf(0.5 + 0.5 * level))


def half_width(se_log, level: float = 0.9):
    """Relative half-width (high - low) / (2 value) of exp(log value +- z se): sinh(z se)."""
    return np.sinh(z_value(level) * np.asarray(se_log, float))


def se_for_width(precision: float, level: float = 0.9) -> float:
    """The se of log(term) whose interval has relative half-width ``precision``."""
    return float(np.arcsinh(precision) / z_value(level))


def octave_grid(n: int, fs: float, tau_min: float | None = None) -> tuple[tuple, tuple]:
    """Cluster sizes and term counts of the octave fit of an ``n``-sample gap-free record
    (the grid of ``allan_deviation(..., taus="octave")``), from ``tau_min`` s on."""
    ms = np.array(cluster_sizes(int(n), "octave"), dtype=np.int64)
    if tau_min is not None:
        ms = ms[ms >= tau_min * fs * (1.0 - 1e-9)]
    counts = static_counts(int(n), tuple(int(m) for m in ms), "oadev")
    return tuple(int(m) for m in ms), tuple(float(c) for c in counts)


def expected_data(params, fs: float, n: int, *, tau_min: float | None = None) -> AllanFitData:
    """The :class:`AllanFitData` an ``n``-sample record would give on average: model AVAR
    as ``avar``, the model EDF as ``edf`` and the covariance tensors of its grid."""
    ms, counts = octave_grid(n, fs, tau_min)
    if not ms:
        raise PlanError(f"{n} samples at {fs:g} Hz give no octave tau from "
                        f"{(1.0 / fs if tau_min is None else tau_min):g} s on",
                        fix="plan a longer record")
    tensors = covariance_tensors(ms, counts)
    tau = np.array(ms, float) / fs
    p = np.asarray(tuple(params), float)
    data = AllanFitData(tau, np.asarray(avar(p, tau)), np.full(tau.size, np.nan),
                        np.array(counts), float(fs), int(n), tensors, np.zeros(5))
    _, nu, _ = model_moments(_logp(p), (p > 0).astype(float), data)
    return data._replace(edf=np.asarray(nu))


def _logp(p: np.ndarray) -> np.ndarray:
    return np.where(p > 0, np.log(np.where(p > 0, p, 1.0)), 0.0)


def _check_params(params, terms) -> tuple[np.ndarray, tuple]:
    p = np.asarray(tuple(AllanParams(*params)), float)
    terms = tuple(t for t in TERMS if t in (terms or [t for t, v in zip(TERMS, p) if v > 0]))
    bad = [t for t in terms if not (np.isfinite(p[TERMS.index(t)]) and p[TERMS.index(t)] > 0)]
    if bad or not terms:
        raise PlanError(f"the model's terms must have positive values, got "
                        f"{dict(zip(TERMS, p.tolist()))} for terms {list(terms)}",
                        column="params", fix="give every term of the model a value > 0 "
                                             "(leave absent terms out of the model)")
    mask = np.array([t in terms for t in TERMS], float)
    return p * mask, terms


def log_cov(params, data: AllanFitData, terms=None) -> tuple[tuple, np.ndarray]:
    """The model's terms and the covariance (J^T V^-1 J + 1/s0^2)^-1 of their log values on
    the tau grid of ``data`` at ``params`` (module docstring); on a measured record's
    :class:`AllanFitData` at its GLS estimate this is the fit's own covariance."""
    p, terms = _check_params(params, terms)
    mask = (p > 0).astype(float)
    _, nu, corr = model_moments(_logp(p), mask, data)
    _, v = log_moments(np.asarray(nu))
    sd = np.sqrt(np.asarray(v))
    prec = np.linalg.inv(np.asarray(corr) * np.outer(sd, sd))
    parts = np.asarray(term_avar(p, data.tau))  # (5, K)
    J = (2.0 * parts / parts.sum(axis=0)).T  # d log sigma^2 / d log p
    on = mask > 0
    Jm = J[:, on]
    info = Jm.T @ prec @ Jm + np.eye(int(on.sum())) / PENALTY_SD**2
    return tuple(t for t in TERMS if t in terms), np.linalg.inv(info)


def log_se(params, data: AllanFitData, terms=None) -> dict:
    """Predicted se of log(term) for each term of the model on the tau grid of ``data``:
    sqrt(diag((J^T V^-1 J + 1/s0^2)^-1)) at ``params`` (module docstring)."""
    names, cov = log_cov(params, data, terms)
    return dict(zip(names, np.sqrt(np.diag(cov)).tolist()))


def predicted_se(params, fs: float, n: int, terms=None, *, tau_min: float | None = None) -> dict:
    """Predicted se of log(term) per term for a gap-free ``n``-sample record at ``fs`` Hz."""
    p, terms = _check_params(params, terms)
    return log_se(p, expected_data(p, fs, n, tau_min=tau_min), terms)


def predicted_width(params, fs: float, n: int, term: str, *, level: float = 0.9,
                    terms=None, tau_min: float | None = None) -> float:
    """Predicted relative half-width sinh(z se) of ``term`` for an ``n``-sample record."""
    return float(half_width(predicted_se(params, fs, n, terms, tau_min=tau_min)[term], level))


def shortest_record(fs: float, terms, tau_min: float | None = None) -> int:
    """Fewest samples whose octave grid has max(MIN_TAUS, terms + 1) taus from ``tau_min``."""
    m0 = 1 if tau_min is None else max(1, int(math.ceil(tau_min * fs * (1.0 - 1e-9))))
    m0 = 1 << (m0 - 1).bit_length()  # octave grid: the first power of 2 >= tau_min fs
    k = max(MIN_TAUS, len(terms) + 1)
    return 4 * m0 * (1 << (k - 1)) - 1  # m_max = (n + 1) // 4 reaches m0 2^(k-1)


def _validate(term: str, precision: float, level: float, max_days: float) -> None:
    if term not in TERMS:
        raise PlanError(f"unknown term '{term}'", column="term",
                        fix=f"use one of {', '.join(TERMS)}")
    if not (np.isfinite(precision) and 0.0 < precision < 1.0):
        raise PlanError(f"the precision must be a fraction in (0, 1), got {precision:g}",
                        column="precision", fix="give e.g. 0.10 for +-10 %")
    if not (np.isfinite(level) and 0.0 < level < 1.0):
        raise PlanError(f"the confidence level must lie in (0, 1), got {level:g}",
                        column="level", fix="give e.g. 0.90")
    if not (np.isfinite(max_days) and max_days > 0):
        raise PlanError(f"max_days must be positive, got {max_days:g}", column="max_days",
                        fix=f"give e.g. {MAX_DAYS:g}")


def grid_length(n_lo: int, j: int, steps: int = STEPS) -> int:
    """Length j of the search grid: n + 1 = (n_lo + 1) 2^(j / steps), rounded."""
    return int(round((n_lo + 1) * 2.0 ** (j / steps))) - 1


def search_length(se_of_n, target: float, n_lo: int, n_max: int,
                  steps: int = STEPS) -> tuple[int | None, int]:
    """Shortest grid length n in [n_lo, n_max] with ``se_of_n(n) <= target`` (None if none
    is); also returns the number of evaluations. ``se_of_n`` must not increase with n."""
    evals, j, prev = 1, 0, None
    while se_of_n(grid_length(n_lo, j, steps)) > target:
        if grid_length(n_lo, j, steps) >= n_max:
            return None, evals
        prev, j = j, j + steps
        evals += 1
    if prev is not None:
        lo, hi = prev, j  # se(lo) > target >= se(hi)
        while hi - lo > 1:
            mid = (lo + hi) // 2
            evals += 1
            if se_of_n(grid_length(n_lo, mid, steps)) <= target:
                hi = mid
            else:
                lo = mid
        j = hi
    n = grid_length(n_lo, j, steps)
    return (n if n <= n_max else None), evals


def plan_length(params, fs: float, term: str, precision: float, *, level: float = 0.9,
                terms=None, tau_min: float | None = None, max_days: float = MAX_DAYS,
                refuse: bool = True) -> LengthPlan | None:
    """Shortest gap-free record at ``fs`` Hz whose octave GLS fit gives ``term`` a relative
    half-width (high - low) / (2 value) <= ``precision`` at ``level``, for noise ``params``
    (an :class:`~fogbayes.allan.model.AllanParams`, canonical units: e.g. datasheet values).

    ``terms`` is the model fitted (default: the terms with a positive value); ``tau_min``
    the shortest tau the fit keeps (default 1/fs). A target that needs more than
    ``max_days`` days raises :class:`PlanError` (or returns None with ``refuse=False``).
    The length is found to 0.54 % (the search grid of the module docstring).

    Example:
        >>> p = plan_length(AllanParams(Q=0.19, N=0.01, B=0.165, K=0.66), 10.0, "K", 0.10)
        >>> round(p.hours, 1), p.half_width <= 0.10, p.n_taus
        (40.7, True, 19)
    """
    _validate(term, float(precision), float(level), float(max_days))
    if not (np.isfinite(fs) and fs > 0):
        raise PlanError(f"the sample rate must be positive, got {fs}", column="fs",
                        fix="give fs in Hz")
    p, terms = _check_params(params, terms)
    if term not in terms:
        raise PlanError(f"term {term} is not in the model ({', '.join(terms)})", column="term",
                        fix=f"give {term} a value, or plan one of {', '.join(terms)}")
    target = se_for_width(float(precision), float(level))
    n_lo = shortest_record(fs, terms, tau_min)
    n_max = int(math.ceil(max_days * 86400.0 * fs))
    n, _ = search_length(lambda k: predicted_se(p, fs, k, terms, tau_min=tau_min)[term],
                         target, n_lo, max(n_max, n_lo))
    if n is None:
        if not refuse:
            return None
        w = predicted_width(p, fs, max(n_max, n_lo), term, level=level, terms=terms,
                            tau_min=tau_min)
        raise PlanError(
            f"{term} to +-{precision:.3g} at {level:.0%} needs more than {max_days:g} days at "
            f"{fs:g} Hz (a {max_days:g}-day record gives +-{w:.3g})", column="precision",
            fix=f"ask for a looser precision (>= {w:.2g}) or a lower confidence level")
    se = predicted_se(p, fs, n, terms, tau_min=tau_min)[term]
    ms, _ = octave_grid(n, fs, tau_min)
    return LengthPlan(term, float(precision), float(level), int(n), float(fs), n / fs,
                      n / fs / 3600.0, float(se), float(half_width(se, level)), terms,
                      AllanParams(*p), ms[-1] / fs, len(ms), n == n_lo)


def describe(plan: LengthPlan) -> dict:
    """JSON-able form of a :class:`LengthPlan`."""
    return {"term": plan.term, "unit": UNITS[plan.term], "precision": plan.precision,
            "level": plan.level, "n": plan.n, "fs": plan.fs, "seconds": plan.seconds,
            "hours": plan.hours, "se_log": plan.se_log, "half_width": plan.half_width,
            "terms": list(plan.terms), "params": dict(zip(TERMS, plan.params)),
            "tau_max": plan.tau_max, "n_taus": plan.n_taus, "at_minimum": plan.at_minimum}
