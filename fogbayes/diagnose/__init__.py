"""Residuals -> findings: candidate effects, evidence under coloured noise, model-free scans.

* :mod:`.candidates` -- every docs/DESIGN.md effect name as a family of model terms;
* :mod:`.evidence` -- bootstrap-calibrated screening under the state-space noise model;
* :mod:`.reml` -- restricted-likelihood noise hyperparameters for the null simulations;
* :mod:`.compete` -- candidates that explain the same residual, ranked by a bootstrap duel;
* :mod:`.markov` -- one more Gauss-Markov noise component (start, refit, chi^2_2 p);
* :mod:`.elpd` -- PSIS-LOO / WAIC through ArviZ;
* :mod:`.scans` -- structure no candidate names (``unexplained``);
* :mod:`.covariates` / :mod:`.corners` -- the block grid and the drivers, dT/dt with the
  chamber programme's corners kept;
* :mod:`.refine` -- a searched value refined before the decision and polished after it;
* :mod:`.noise_prior` -- a cap on the random walk from a static run (``--noise-prior``).
"""

from .candidates import EFFECTS, Candidate, candidates_for
from .context import Context, make_context
from .fitting import ModelFit, fit_terms
from .noise_prior import NoisePrior, read_noise_prior
from .terms import Term

__all__ = ["EFFECTS", "Candidate", "Context", "ModelFit", "NoisePrior", "Term",
           "candidates_for", "fit_terms", "make_context", "read_noise_prior"]
