"""Workflows: the order of the stages for each model family.

``fit_recording(rec, *, model, orders=None, bayes=False, seed=0, **options) -> dict`` and
``compensate_recording(rec, fit)`` in :mod:`fogbayes.thermal.workflow`,
:mod:`fogbayes.composite.workflow`, :mod:`fogbayes.allan.workflow`, :mod:`fogbayes.arma.workflow`;
:func:`workflow_for` imports one lazily.
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
        raise FogbayesError(f"unknown model '{model}'", flag="--model",
                            fix=f"use one of {', '.join(MODULES)}")
    return importlib.import_module(MODULES[model], __name__)
