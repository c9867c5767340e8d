"""The one convergence rule of every posterior fogbayes samples.

converged = max R-hat < 1.01 and min bulk ESS >= floor and no divergent transition (rank-normalised
split R-hat and bulk ESS, Vehtari et al. 2021; default floor 100 per chain, Allan and population
posteriors 200 in all). A non-finite R-hat or ESS fails.
"""

from __future__ import annotations

import math

R_HAT_MAX = 1.01
ESS_PER_CHAIN = 100.0


def ess_floor(num_chains: int) -> float:
    """The default bulk-ESS floor: 100 per chain."""
    return ESS_PER_CHAIN * int(num_chains)


def converged(r_hat_max: float, ess_min: float, divergences: int, *, floor: float) -> bool:
    """The rule of the module doc."""
    r, e = float(r_hat_max), float(ess_min)
    return bool(math.isfinite(r) and math.isfinite(e) and r < R_HAT_MAX and e >= floor
                and int(divergences) == 0)
