"""Residuals -> findings: candidate effects, evidence under coloured noise, model-free scans.

:mod:`.candidates` (effects as model terms), :mod:`.evidence` (bootstrap-calibrated screening),
:mod:`.reml`, :mod:`.compete` (duels), :mod:`.markov`, :mod:`.elpd`, :mod:`.scans`
(``unexplained``), :mod:`.covariates` / :mod:`.corners` (block grid, dT/dt), :mod:`.refine`,
:mod:`.noise_prior` (``--noise-prior``).
"""

from .candidates import EFFECTS, Candidate, candidates_for
from .context import Context, make_context
from .fitting import ModelFit, fit_terms
from .noise_prior import NoisePrior, read_noise_prior
from ..effects.terms import Term

__all__ = ["EFFECTS", "Candidate", "Context", "ModelFit", "NoisePrior", "Term",
           "candidates_for", "fit_terms", "make_context", "read_noise_prior"]
