"""``markov_noise``: does one more first-order Gauss-Markov component improve the noise model?

Screening keeps the current noise hyperparameters theta and adds a component of
relative variance v and time constant tau_c on a grid (tau_c log-spaced from 2 dt to a
quarter of the record, v from 1e-3 to 1e3 of the white block variance)::

    stat(tau_c) = 2 max_v [ logL(theta, v, tau_c) - logL(theta, v = 0) ]

For a fixed tau_c the variance sits on the boundary of its space under the null, so the
statistic is a 50:50 mixture of chi^2_0 and chi^2_1 (Self & Liang 1987): p = 0.5 P(chi^2_1 > stat).
The minimum p over the tau_c grid is calibrated like every searched parameter, by the
same statistic on series simulated from the fitted noise model (one compiled, vmapped
call evaluates the whole (tau_c, v) grid on the data and on every simulated series).

The decision uses the *refitted* ratio (every noise hyperparameter re-estimated, the
screening optimum as a start), whose null distribution is heavier than the fixed-noise
one: measured by running the loop on 56 pure-noise records (four noise mixes, 3-6 h,
1-10 Hz) it has mean 1.8, 7 % above 5 and 1 of 56 above 8.3 -- a chi^2_2 (mean 2,
P(> 5) = 8 %, P(> 8.3) = 1.6 %), not the fixed-tau mixture. :func:`markov_log_p` uses chi^2_2.
"""

from __future__ import annotations

import math

import jax.numpy as jnp
import numpy as np
from scipy import stats

from ..inference import noise_ssm as ns
from . import nullsim
from .candidates import Candidate
from .context import Context
from .evidence import Screened, Whitened, _m_eff, calibrated_log_p
from .fitting import ModelFit
from .terms import Term, design

N_TAU, N_VAR = 8, 13


def _alt(spec: ns.NoiseSpec) -> ns.NoiseSpec:
    return spec._replace(n_markov=spec.n_markov + 1)


def _alt_theta(spec: ns.NoiseSpec, theta: np.ndarray, logvar: float, logtau: float) -> np.ndarray:
    """theta of the alternative spec: the current values plus one (logvar, logtau) pair."""
    p = ns.unpack(spec, theta)
    alt = _alt(spec)
    q = ns.NoiseParams(p.log_flicker, p.log_rw,
                       jnp.concatenate([p.markov_logvar, jnp.array([logvar])]),
                       jnp.concatenate([p.markov_logtau, jnp.array([logtau])]))
    return ns.pack(alt, q)


def _grid(ctx: Context, spec: ns.NoiseSpec) -> tuple[np.ndarray, np.ndarray] | None:
    """(tau_c, v) screening grid inside the spec's bounds (a noise prior may cap both)."""
    lo_tau = 2.0 * ctx.grid.dt
    hi_tau = min(max(ctx.cov.duration / 4.0, 8.0 * ctx.grid.dt), spec.tau_max)
    hi_v = min(1e3, math.exp(spec.log_mvar_max))
    if hi_tau <= lo_tau or hi_v <= 1e-3:
        return None
    return np.geomspace(lo_tau, hi_tau, N_TAU), np.geomspace(1e-3, hi_v, N_VAR)


def screen_markov(ctx: Context, fit: ModelFit, wm: Whitened, *, n_sims: int = 100,
                  seed: int = 0) -> Screened | None:
    """Screen ``markov_noise`` (see module doc); None if the record is too short for it,
    or a noise prior leaves no room for it."""
    spec, theta = fit.noise.spec, fit.noise.theta
    grid = _grid(ctx, spec)
    if grid is None:
        return None
    taus, vs = grid
    alt = _alt(spec)
    thetas = [_alt_theta(spec, theta, -60.0, math.log(taus[0]))]
    thetas += [_alt_theta(spec, theta, math.log(v), math.log(t)) for t in taus for v in vs]
    sims = nullsim.simulate(spec, theta, 1.0, ctx.grid.w, n_sims, seed=seed + 17)
    Ycols = np.column_stack([np.where(ctx.grid.mask > 0, ctx.y, 0.0), sims])
    Xp, pad = ns.pad_columns(fit.X)
    ll = np.asarray(nullsim.column_logliks(alt, jnp.asarray(np.array(thetas)), jnp.asarray(Ycols),
                                      jnp.asarray(Xp), jnp.asarray(ctx.grid.mask),
                                      jnp.asarray(ctx.grid.w), jnp.asarray(pad)))
    gain = 2.0 * (ll[1:] - ll[:1]).reshape(N_TAU, N_VAR, -1)   # (tau, v, column)
    per_tau = np.maximum(gain.max(axis=1), 0.0)                 # (tau, column)
    logp = np.where(per_tau > 0, math.log(0.5) + stats.chi2.logsf(per_tau, 1), 0.0)
    lp_min = logp.min(axis=0)
    m = _m_eff(lp_min[1:], N_TAU)
    it = int(np.argmin(logp[:, 0]))
    iv = int(np.argmax(gain[it, :, 0]))
    best = Term("markov", {"effect": "markov_noise", "tau": float(taus[it]),
                           "logvar": float(math.log(vs[iv]))})
    cand = Candidate("markov_noise", "noise", (), ("noise",), "tau_c")
    return Screened(cand, best, float(taus[it]), float(per_tau[it, 0]), 1, float(lp_min[0]), m,
                    calibrated_log_p(float(lp_min[0]), m))


def markov_log_p(lr: float) -> float:
    """log p of a refitted markov_noise likelihood ratio: chi^2_2 (see the module doc)."""
    return -0.5 * max(lr, 0.0)


def refit_markov(ctx: Context, fit: ModelFit, s: Screened) -> ModelFit:
    """The model with one more Gauss-Markov component, all noise hyperparameters refitted."""
    spec, alt = fit.noise.spec, _alt(fit.noise.spec)
    start = _alt_theta(spec, fit.noise.theta, s.best.params["logvar"], math.log(s.best.params["tau"]))
    nf = ns.fit_noise(alt, ctx.y, fit.X, ctx.grid.mask, ctx.grid.w, extra_starts=start[None])
    resid = ctx.rate - design(list(fit.terms), ctx.cov) @ nf.beta
    return ModelFit(fit.terms, fit.X, nf, resid)
