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
"""

from __future__ import annotations

import numpy as np

from ..inference.noise_ssm import unpack
from .context import Context
from .fitting import ModelFit, fit_terms
from .nullsim import simulate

#: log(random-walk / white variance ratio) above which a fit counts as in the walk mode.
RW_MODE = -12.0
#: simulated series per factor: the mean of 20 chi^2-like ratios is known to ~30 %
N_SIMS = 20


def in_walk_mode(fit: ModelFit) -> bool:
    """Whether the fit's noise has a random walk above the mode threshold."""
    spec = fit.noise.spec
    return bool(spec.random_walk and spec.bank_taus
                and float(unpack(spec, fit.noise.theta).log_rw) > RW_MODE)


def leaves_walk_mode(base: ModelFit, alt: ModelFit) -> bool:
    """The refit dropped the walk that the current fit has (the ratio is then not chi^2)."""
    return in_walk_mode(base) and not in_walk_mode(alt)


def bartlett_factor(ctx: Context, base: ModelFit, alt: ModelFit, dof: int, *,
                    n_sims: int = N_SIMS, seed: int = 0) -> float:
    """c = max(1, mean null refitted ratio / dof) under ``base`` (see module doc)."""
    nf = base.noise
    noise = simulate(nf.spec, nf.theta, nf.sigma2, ctx.grid.w, n_sims, seed=seed)
    mean = base.X @ nf.beta
    observed = ctx.grid.mask > 0
    ratios = np.empty(n_sims)
    for k in range(n_sims):
        sim = ctx._replace(y=np.where(observed, mean + noise[:, k], 0.0))
        f0 = fit_terms(sim, base.terms, spec=nf.spec, theta0=nf.theta, residual=False)
        f1 = fit_terms(sim, alt.terms, spec=nf.spec, theta0=nf.theta, residual=False)
        ratios[k] = max(2.0 * (f1.loglik - f0.loglik), 0.0)
    return max(1.0, float(ratios.mean()) / max(dof, 1))
