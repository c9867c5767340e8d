"""The range of planned lengths that uncertain noise values allow.

[min, max] of n*(theta) over E = {(theta - theta_hat)' Sigma^-1 (theta - theta_hat) <= z^2},
z = 1.645 (the pilot's 90 % region, Sigma its GLS covariance). Since se falls with n, the max is
the shortest n with max_E se(theta, n) <= target (:func:`~fogbayes.plan.length.search_length`),
found by theta <- theta_hat +- z Sigma g / sqrt(g'Sigma g), g = grad log se.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from ..allan.model import TERMS, AllanParams
from .length import MAX_DAYS, _check_params, predicted_se, se_for_width, search_length, \
    shortest_record, z_value

#: Confidence of the region of the noise values (the pilot's intervals are 90 %).
REGION_LEVEL = 0.9
_STEP = 1e-4  # forward-difference step in log value
_ITER = 5


class PlanRange(NamedTuple):
    """Shortest and longest plan over the region (n None = beyond max_days)."""

    n_low: int | None
    n_high: int | None
    params_low: AllanParams   # the values in the region that give the shortest plan
    params_high: AllanParams  # ... the longest plan
    fs: float

    @property
    def hours(self) -> tuple[float, float]:
        f = lambda n: math.inf if n is None else n / self.fs / 3600.0  # noqa: E731
        return f(self.n_low), f(self.n_high)


def plan_range(params, cov, fs: float, term: str, precision: float, *, level: float = 0.9,
               terms=None, tau_min: float | None = None, max_days: float = MAX_DAYS,
               region_level: float = REGION_LEVEL) -> PlanRange:
    """Range of :func:`~fogbayes.plan.length.plan_length` over the ``region_level`` region
    of log values with covariance ``cov`` (the model's terms in the order of ``TERMS``)
    about ``params`` (module docstring)."""
    p, terms = _check_params(params, terms)
    on = np.array([t in terms for t in TERMS])
    cov = np.asarray(cov, float)
    if cov.shape != (on.sum(), on.sum()):
        raise ValueError(f"cov must be {on.sum()} x {on.sum()} (terms {terms}), got {cov.shape}")
    theta0 = np.log(p[on])
    z = z_value(region_level)
    target = se_for_width(float(precision), float(level))

    def log_se(theta, n):
        q = p.copy()
        q[on] = np.exp(theta)
        return math.log(predicted_se(q, fs, n, terms, tau_min=tau_min)[term])

    def extreme(n, sign):
        best_v, best_th = log_se(theta0, n), theta0
        th = theta0
        for _ in range(_ITER):
            f0 = log_se(th, n)
            g = np.array([(log_se(th + _STEP * e, n) - f0) / _STEP for e in np.eye(th.size)])
            sg = cov @ g
            q = float(np.sqrt(max(g @ sg, 0.0)))
            if not q > 0:
                break
            new = theta0 + sign * z * sg / q
            v = log_se(new, n)
            if sign * v > sign * best_v:
                best_v, best_th = v, new
            if np.max(np.abs(new - th)) < 1e-3:
                break
            th = new
        return math.exp(best_v), best_th

    n_lo = shortest_record(fs, terms, tau_min)
    n_max = max(int(math.ceil(max_days * 86400.0 * fs)), n_lo)
    out = []
    for sign in (-1.0, 1.0):
        n, _ = search_length(lambda k: extreme(k, sign)[0], target, n_lo, n_max)
        th = extreme(n if n is not None else n_max, sign)[1]
        q = p.copy()
        q[on] = np.exp(th)
        out.append((n, AllanParams(*q)))
    return PlanRange(out[0][0], out[1][0], out[0][1], out[1][1], float(fs))
