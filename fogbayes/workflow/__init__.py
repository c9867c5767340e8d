"""Workflows: the order of the stages for each model family, one module in each family's
package.

``fit_recording(rec, *, model, orders=None, bayes=False, seed=0, **options) -> dict`` and
``compensate_recording(rec, fit) -> dict[str, np.ndarray]`` (docs/DESIGN.md / contracts):

* :mod:`fogbayes.thermal.workflow` -- ``bias-t`` and ``thermal`` (paper 004; the family's
  package)
* :mod:`fogbayes.composite.workflow` -- ``composite`` (paper 000; the family's package)
* :mod:`fogbayes.allan.workflow` -- ``allan`` (five-term Allan model)
* :mod:`fogbayes.arma.workflow` -- ``arma`` (paper 002 drift model; nothing to compensate)

:func:`workflow_for` imports the module of a model name lazily, so that the command line
and notebooks pay only for the model they use.
"""

from __future__ import annotations

import importlib
from types import ModuleType

from ..errors import FogbayesError

#: model name -> workflow module (relative to this package)
MODULES = {"bias-t": "..thermal.workflow", "thermal": "..thermal.workflow", "composite": "..composite.workflow",
           "allan": "..allan.workflow", "arma": "..arma.workflow"}


def workflow_for(model: str) -> ModuleType:
    """The workflow module that fits and compensates ``model``."""
    if model not in MODULES:
        raise FogbayesError(f"unknown model '{model}'", column="model",
                            fix=f"use one of {', '.join(MODULES)}")
    return importlib.import_module(MODULES[model], __name__)
