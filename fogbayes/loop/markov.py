"""``markov_noise``: does one more first-order Gauss-Markov noise component improve the fit?

Start: the best point of a (tau_c, v) grid with the other noise hyperparameters kept (one
call), then all refitted. :func:`markov_log_p` refers the refitted likelihood ratio to
chi^2_2 (heavier than the fixed-tau_c mixture of Self & Liang 1987; benchmarks/RESULTS_loop.md).
"""

from __future__ import annotations

import math

import numpy as np

from ..inference import noise_ssm as ns
from ..inference import noise_fit as nfit
from . import nullsim
from .context import Context
from .fitting import ModelFit
from ..effects.simulator_only import MarkovNoise
from ..effects.terms import Term, design

N_TAU, N_VAR = 8, 13


def _alt(spec: ns.NoiseSpec) -> ns.NoiseSpec:
    return spec._replace(n_markov=spec.n_markov + 1)


def _alt_theta(spec: ns.NoiseSpec, theta: np.ndarray, logvar: float, logtau: float) -> np.ndarray:
    """theta of the alternative spec: the current values plus one (logvar, logtau) pair."""
    p = ns.unpack(spec, theta)
    alt = _alt(spec)
    q = ns.NoiseParams(p.log_flicker, p.log_rw,
                       np.concatenate([p.markov_logvar, [logvar]]),
                       np.concatenate([p.markov_logtau, [logtau]]))
    return ns.pack(alt, q)


def _grid(ctx: Context, spec: ns.NoiseSpec) -> tuple[np.ndarray, np.ndarray] | None:
    """(tau_c, v) screening grid inside the spec's bounds (a noise prior may cap both)."""
    lo_tau = 2.0 * ctx.grid.dt
    hi_tau = min(max(ctx.cov.duration / 4.0, 8.0 * ctx.grid.dt), spec.tau_max)
    hi_v = min(1e3, math.exp(spec.log_mvar_max))
    if hi_tau <= lo_tau or hi_v <= 1e-3:
        return None
    return np.geomspace(lo_tau, hi_tau, N_TAU), np.geomspace(1e-3, hi_v, N_VAR)


def markov_start(ctx: Context, fit: ModelFit) -> Term | None:
    """The start of :func:`refit_markov`: the (tau_c, v) grid point of largest likelihood
    with the current noise hyperparameters kept (see module doc); None if the record is
    too short for a component, or a noise prior leaves no room for one."""
    spec, theta = fit.noise.spec, fit.noise.theta
    grid = _grid(ctx, spec)
    if grid is None:
        return None
    taus, vs = grid
    thetas = [_alt_theta(spec, theta, math.log(v), math.log(t)) for t in taus for v in vs]
    ll = nullsim.column_logliks(_alt(spec), np.array(thetas), ctx.y[:, None], fit.X,
                                ctx.grid.mask, ctx.grid.w)
    it, iv = np.unravel_index(int(np.argmax(ll[:, 0])), (N_TAU, N_VAR))
    return Term("markov", {"effect": MarkovNoise.name, "tau": float(taus[it]),
                           "logvar": float(math.log(vs[iv]))})


def markov_log_p(lr: float) -> float:
    """log p of a refitted markov_noise likelihood ratio: chi^2_2 (see the module doc)."""
    return -0.5 * max(lr, 0.0)


def refit_markov(ctx: Context, fit: ModelFit, start_term: Term) -> ModelFit:
    """The model with one more Gauss-Markov component, all noise hyperparameters refitted
    from ``start_term`` (:func:`markov_start`)."""
    spec, alt = fit.noise.spec, _alt(fit.noise.spec)
    start = _alt_theta(spec, fit.noise.theta, start_term.params["logvar"],
                       math.log(start_term.params["tau"]))
    nf = nfit.fit_noise(alt, ctx.y, fit.X, ctx.grid.mask, ctx.grid.w, extra_starts=start[None])
    resid = ctx.rate - design(list(fit.terms), ctx.cov) @ nf.beta
    return ModelFit(fit.terms, fit.X, nf, resid)
