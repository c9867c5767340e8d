"""The one convergence rule of every posterior fogbayes samples::

    converged = max R-hat < 1.01  and  min bulk ESS >= floor  and  no divergent transition

R-hat is the rank-normalised split R-hat and ESS the bulk ESS of Vehtari et al. (2021),
whose advice is R-hat < 1.01 and ESS >= 100 per chain: the default floor. The Allan and
population posteriors ask 200 in all (their K-R ridge and the population spread mix
slowly; :mod:`fogbayes.allan.bayes`). A non-finite R-hat or ESS (a constant chain) fails.
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
