"""Bootstrap Bartlett factor of a refitted likelihood ratio whose noise model changes mode.

The loop refits the model with a candidate term and re-estimates the noise by maximum
likelihood. When the current fit sits in the random-walk mode and the refit drops the walk
(its variance goes to the lower bound: a slow term now carries the wander), the ratio

    LR = 2 (logL_with - logL_without)

is not chi^2_dof under "no effect": the walk variance of a local-level model piles up at zero
whenever a slow regressor is offered, so a walk alone yields ratios of 10-20 for a drift or a
lag in one clean record out of five (benchmarks/RESULTS_loop.md). Its null distribution is
measured instead, by its scale (Bartlett's correction, estimated by a parametric bootstrap;
Rocke 1989):

    c = max(1, mean_k LR_k / dof),   LR_k from series simulated under the current fit,
    LR / c  ~  chi^2_dof

with both models refitted by ML on every simulated series exactly as on the data (the
candidate's searched value held at the refined one: the search is calibrated separately by
the screening's effective number of tests).

The null ratios are right-skewed (most near 0, a few of 10-20 where the walk collapses), so
the mean of 20 is known only to ~30 % and a decision near alpha could turn on the draw
(measured on a 0.2 deg/h step, 200 series: c = 1.38, while 20-series means ranged 0.84-2.10
(5-95 %); the loop had drawn 2.24 and missed the step). Given the decision it feeds
(``decide(c)``: does LR / c pass?), the estimate is *sequential*: after every batch of 5
series, if the decision is the same at c = mean / dof +- 2 standard errors it stops, else 5
more are drawn, up to ``n_max`` (100: a standard error of ~13 %). The standard error is
never taken below what the factor's own model implies (LR / c ~ chi^2_dof has variance
2 dof c^2), so a few ratios that happen to agree cannot settle a close decision, while a
decision far from the threshold -- most of them -- costs 5 series instead of 20.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ..inference.noise_fit import fit_noise_many
from ..inference.noise_ssm import unpack
from .context import Context
from .fitting import ModelFit
from .nullsim import simulate

#: log(random-walk / white variance ratio) above which a fit counts as in the walk mode.
RW_MODE = -12.0
#: simulated series per batch of the sequential estimate (module doc)
N_SIMS = 5
#: most series per factor, when the decision is still open at +- 2 standard errors
N_MAX = 100
#: seed offset between batches
BATCH_SEED = 1_000_003


def in_walk_mode(fit: ModelFit) -> bool:
    """Whether the fit's noise has a random walk above the mode threshold."""
    spec = fit.noise.spec
    return bool(spec.random_walk and spec.bank_taus
                and float(unpack(spec, fit.noise.theta).log_rw) > RW_MODE)


def leaves_walk_mode(base: ModelFit, alt: ModelFit) -> bool:
    """The refit dropped the walk that the current fit has (the ratio is then not chi^2)."""
    return in_walk_mode(base) and not in_walk_mode(alt)


def null_ratios(ctx: Context, base: ModelFit, alt: ModelFit, n_sims: int, *,
                seed: int) -> np.ndarray:
    """Refitted ratios 2(logL_alt - logL_base) of ``n_sims`` series simulated under ``base``.

    Both models are refitted on every series as :func:`~fogbayes.diagnose.fitting.fit_terms` would (the same starts,
    the base fit's noise hyperparameters among them); the 2 ``n_sims`` fits run in lockstep
    (:func:`fogbayes.inference.noise_fit.fit_noise_many`)."""
    nf = base.noise
    noise = simulate(nf.spec, nf.theta, nf.sigma2, ctx.grid.w, n_sims, seed=seed)
    mean = base.X @ nf.beta
    observed = ctx.grid.mask > 0
    ys = [np.where(observed, mean + noise[:, k], 0.0) for k in range(n_sims)]
    X0, X1 = ctx.block_design(list(base.terms)), ctx.block_design(list(alt.terms))
    fits = fit_noise_many(nf.spec, [y for y in ys for _ in (0, 1)], [X0, X1] * n_sims,
                          ctx.grid.mask, ctx.grid.w,
                          extra_starts=[np.atleast_2d(nf.theta)] * (2 * n_sims))
    ll = np.array([f.loglik for f in fits]).reshape(n_sims, 2)
    return np.maximum(2.0 * (ll[:, 1] - ll[:, 0]), 0.0)


def bartlett_factor(ctx: Context, base: ModelFit, alt: ModelFit, dof: int, *,
                    n_sims: int = N_SIMS, n_max: int = N_MAX, seed: int = 0,
                    decide: Callable[[float], bool] | None = None) -> float:
    """c = max(1, mean null refitted ratio / dof) under ``base`` (see module doc).

    Without ``decide``: the mean of one batch of ``n_sims`` series. With it: batches (batch
    b seeded ``seed + BATCH_SEED * b``, so the first is the one without ``decide``) until
    ``decide`` agrees at c -+ 2 standard errors (at least the chi^2 model's, module doc) or
    ``n_max`` series are used.
    """
    dof = max(dof, 1)
    ratios = null_ratios(ctx, base, alt, n_sims, seed=seed)
    while decide is not None and ratios.size + n_sims <= n_max:
        c_hat = max(1.0, float(ratios.mean()) / dof)
        se = max(float(ratios.std(ddof=1)), c_hat * np.sqrt(2.0 * dof)) / np.sqrt(ratios.size)
        lo, hi = (max(1.0, (float(ratios.mean()) + d * se) / dof) for d in (-2.0, 2.0))
        if decide(lo) == decide(hi):
            break
        batch = null_ratios(ctx, base, alt, n_sims, seed=seed + BATCH_SEED * (ratios.size // n_sims))
        ratios = np.concatenate([ratios, batch])
    return max(1.0, float(ratios.mean()) / dof)
