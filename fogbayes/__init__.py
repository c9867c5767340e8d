"""fogbayes: probabilistic modelling of fiber-optic-gyroscope errors.

Importing fogbayes turns on JAX float64 (see :mod:`fogbayes._config`). Beside load, save
and Recording it offers fit, compensate, run_loop, allan_deviation
(:mod:`fogbayes.workflow.api`) and report (:func:`fogbayes.workflow.report.report`), imported on first use.
"""

from . import _config  # noqa: F401  (float64 on before any JAX array is made)
from .data import Metadata, Recording, load, save
from .errors import FogbayesError

__version__ = "0.1.0"
__all__ = ["FogbayesError", "Metadata", "Recording", "allan_deviation", "compensate", "fit",
           "load", "report", "run_loop", "save", "__version__"]

def __getattr__(name: str):
    """The flat API (fogbayes.workflow.api.LAZY), resolved on first use: importing fogbayes
    stays light."""
    from .workflow.api import LAZY

    if name in LAZY:
        import importlib

        module, attr = LAZY[name]
        value = getattr(importlib.import_module(module), attr)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'fogbayes' has no attribute {name!r}")
