r"""Rate random walk K from the time-domain likelihood, with a profile-likelihood interval.

A study, not a library method (``coverage_allan.py --methods ssm``): measured against the
Allan GLS fit it is no clear gain (benchmarks/RESULTS_allan.md, section 3, 2026-11-22 (e9458e2)
rerun): somewhat smaller error on mix A, intervals too narrow on mix B.

Why: the Allan variance condenses the record into a few octaves, and K rests on the last
two or three of them, which under a random walk are correlated ~0.9 and carry a handful of
degrees of freedom (benchmarks/RESULTS_allan.md section 3). The exact Gaussian likelihood
of the record itself uses every increment of the walk.

Model of the block means :math:`\bar y_b` (blocks of ``m`` samples, :math:`T_b = m/f_s`)::

    y_b = mu + w_b + f_b + r_b
    w_b ~ N(0, a)                   white (angle random walk N, and what Q leaves at T_b)
    f_b = sum_j s_{b,j}             flicker bank (bias instability B): first-order Markov
                                    states, time constants sqrt(10) apart from T_b/2 to
                                    2 x the record, one shared variance (noise_ssm)
    r_{b+1} = r_b + e_b,  e_b ~ N(0, K_s^2 T_b)     rate random walk,  K = 60 K_s deg/h^1.5

The likelihood comes from the Kalman filter of :mod:`fogbayes.inference.noise_ssm` (O(n)),
with ``mu`` profiled out by GLS and all three variances free (absolute, log scale). The
estimate is the maximum; the interval is the profile-likelihood interval
:math:`\{K: 2[\ell_{max} - \max_{a, f} \ell(a, f, K)] \le \chi^2_{1, level}\}`, lower end
0 when the walk is not resolved. Block means of a walk are not exactly a sampled walk (the
averaging adds a lag-1 correlation of 1/4 to its increments), so ``T_b`` is kept well
below the white/walk crossover, where that part is a small fraction of the white noise.
"""

from __future__ import annotations

import math
from functools import partial
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from scipy import optimize, stats

from fogbayes.errors import TooShortError
from fogbayes.inference.noise_ssm import NoiseParams, NoiseSpec, _filter, make_spec, system

MAX_BLOCKS = 4096  # Kalman steps per likelihood: ~ms each once compiled


class WalkEstimate(NamedTuple):
    """K (deg/h^1.5) with its profile-likelihood interval; the fit it came from."""

    value: float
    low: float
    high: float
    block_s: float
    loglik: float
    converged: bool


def _negll(spec: NoiseSpec, params, y, mask):
    """-log L of block means y, mu profiled; params = (log a, log f/a, log r): white
    variance, flicker variance relative to it, walk increment variance (absolute)."""
    la, lfr, lr = params[0], params[1], params[2]
    p = NoiseParams(lfr, lr - la, jnp.zeros(0), jnp.zeros(0))
    phi, q, p0 = system(spec, p)
    Y = jnp.stack([y, jnp.ones_like(y)], axis=1) * mask[:, None]
    V, F = _filter(phi, q, p0, Y, mask, jnp.ones_like(y))  # relative to a
    g = mask / F
    syy, sxy, sxx = jnp.sum(g * V[:, 0] ** 2), jnp.sum(g * V[:, 0] * V[:, 1]), jnp.sum(g * V[:, 1] ** 2)
    rss = syy - sxy**2 / sxx
    nobs = mask.sum()
    return 0.5 * (nobs * (jnp.log(2 * jnp.pi) + la) + jnp.sum(mask * jnp.log(F)) + rss / jnp.exp(la))


@partial(jax.jit, static_argnums=0)
def _value_and_grad(spec, params, y, mask):
    return jax.value_and_grad(lambda p: _negll(spec, p, y, mask))(params)


def _minimise(spec, y, mask, x0, box, fixed_lr=None):
    """Minimum of -log L over (log a, log f/a, log r), or over the first two at a fixed log r.

    ``box``: (lo, hi) bounds; the white variance is kept above 1e-6 of the scale of the
    block-to-block differences (at 0 the filter's relative variances overflow)."""
    lo, hi = box

    def fun(x):
        full = x if fixed_lr is None else np.array([x[0], x[1], fixed_lr])
        v, g = _value_and_grad(spec, jnp.asarray(full), y, mask)
        v, g = float(v), np.asarray(g, float)
        if not np.isfinite(v) or not np.all(np.isfinite(g)):
            return 1e300, np.zeros_like(x)
        return v, (g if fixed_lr is None else g[:2])

    n = 3 if fixed_lr is None else 2
    r = optimize.minimize(fun, np.asarray(x0, float)[:n], jac=True, method="L-BFGS-B",
                          bounds=list(zip(lo[:n], hi[:n])), options={"maxiter": 300})
    return r


def block_means(y: np.ndarray, m: int) -> tuple[np.ndarray, np.ndarray]:
    """Means of consecutive m-sample blocks (NaN samples left out) and the observed mask."""
    nb = y.size // m
    b = y[:nb * m].reshape(nb, m)
    ok = np.isfinite(b)
    cnt = ok.sum(axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        means = np.where(cnt > 0, np.where(ok, b, 0.0).sum(axis=1) / cnt, 0.0)
    return means, (cnt == m).astype(float)  # partial blocks count as missing (white weight)


def fit_walk(y, fs: float, *, level: float = 0.9, max_blocks: int = MAX_BLOCKS) -> WalkEstimate:
    """K (deg/h^1.5) of rate samples ``y`` (deg/h) at ``fs`` Hz, with a ``level`` interval."""
    y = np.asarray(y, float)
    m = max(1, math.ceil(y.size / max_blocks))
    yb, mask = block_means(y, m)
    if mask.sum() < 64:
        raise TooShortError(f"{int(mask.sum())} complete blocks of {m} samples: too few for "
                            "the time-domain walk estimate", column="output",
                            fix="record longer (the walk shows over hundreds of blocks)")
    tb = m / float(fs)
    spec = make_spec(tb, yb.size * tb, random_walk=True, flicker=True)
    yc = jnp.asarray(np.where(mask > 0, yb - np.mean(yb[mask > 0]), 0.0))
    mk = jnp.asarray(mask)
    a0 = math.log(max(np.var(np.diff(yb[mask > 0])) / 2, 1e-30))
    box = (np.array([a0 - 14.0, -25.0, a0 - 40.0]), np.array([a0 + 5.0, 12.0, a0 + 10.0]))
    best = None
    for lf in (-5.0, 0.0):
        for lr in (a0 - 12, a0 - 5):
            r = _minimise(spec, yc, mk, [a0, lf, lr], box)
            if best is None or r.fun < best.fun:
                best = r
    x, nll = best.x, float(best.fun)
    thr = stats.chi2.ppf(level, 1) / 2.0

    def excess(lr):  # profile -log L above the minimum, minus the threshold
        return _minimise(spec, yc, mk, x[:2], box, fixed_lr=lr).fun - nll - thr

    def end(direction):
        step, lr0 = 1.0, x[2]
        prev = lr0
        for _ in range(40):
            cand = prev + direction * step
            if cand < box[0][2] or cand > box[1][2]:
                return None
            if excess(cand) > 0:
                return optimize.brentq(excess, min(prev, cand), max(prev, cand), xtol=1e-3)
            prev, step = cand, step * 1.5
        return None

    lo_lr, hi_lr = end(-1.0), end(+1.0)

    def k_of(lr):
        return 60.0 * math.sqrt(math.exp(lr) / tb)

    return WalkEstimate(k_of(x[2]), 0.0 if lo_lr is None else k_of(lo_lr),
                        math.inf if hi_lr is None else k_of(hi_lr), tb, -nll,
                        bool(best.success or best.status == 0) and hi_lr is not None)
