"""Bootstrap Bartlett factor of a refitted likelihood ratio whose noise model changes mode.

When a refit drops the random walk (a slow term carries the wander), LR = 2 (logL_with -
logL_without) is not chi^2_dof under the null. Its scale is estimated by parametric bootstrap
(Rocke 1989): c = max(1, mean_k LR_k / dof) over series simulated under the current fit, both
models refitted by ML, and LR / c ~ chi^2_dof. Sequential: batches of 5 until the decision
``decide(c)`` is the same at c +- 2 standard errors (floored at the chi^2 model's own, variance
2 dof c^2), at most ``n_max``.
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

    Both models are refitted on every series as :func:`~fogbayes.loop.fitting.fit_terms`
    would (the same starts, the base fit's noise hyperparameters among them); the 2 ``n_sims`` fits share one
    block grid (:func:`fogbayes.inference.noise_fit.fit_noise_many`)."""
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
