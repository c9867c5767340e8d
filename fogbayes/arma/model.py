"""ARMA(p, q) noise model: exact Gaussian likelihood, stationary/invertible parameterisation.

Re-exports :mod:`fogbayes.models.arma` (paper 002 eq. 8, its sign convention), which the shared
layer (:mod:`fogbayes.inference`) also uses.
"""

from __future__ import annotations

from ..models.arma import (  # noqa: F401 -- re-exported: the family's model
    SIGN_CONVENTION,
    Array,
    ArmaParams,
    allpole_filter,
    ar_to_pacf,
    arma_acov,
    arma_loglik,
    arma_profile_loglik,
    pacf_to_ar,
    params_to_unconstrained,
    profile_terms,
    unconstrained_to_params,
)
