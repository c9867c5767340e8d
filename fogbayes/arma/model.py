"""ARMA(p, q) noise model of the ARMA family: the exact Gaussian likelihood and the
stationary/invertible parameterisation (paper 002, eq. 8, its sign convention).

The functions live in :mod:`fogbayes.models.arma` (the derivation is there): the shared
layer below the families uses them too (:mod:`fogbayes.inference.bayes`'s ARMA noise), and
imports point one way, so :mod:`fogbayes.inference` never imports a family. The names are
the same here.
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
