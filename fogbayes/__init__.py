"""fogbayes: probabilistic modelling of fiber-optic-gyroscope errors.

Importing fogbayes turns on JAX float64 (see :mod:`fogbayes._config`). Beside load, save
and Recording it offers fit, compensate, run_loop and allan_deviation
(:mod:`fogbayes.workflow.api`), imported on first use.
"""

from . import _config  # noqa: F401  (float64 on before any JAX array is made)
from .data import Metadata, Recording, load, save
from .errors import FogbayesError

__version__ = "0.1.0"
__all__ = ["FogbayesError", "Metadata", "Recording", "allan_deviation", "compensate", "fit",
           "load", "run_loop", "save", "__version__"]

#: the flat API resolved on first use (fogbayes.workflow.api): importing fogbayes stays light
_LAZY = {"fit", "compensate", "run_loop", "allan_deviation"}


def __getattr__(name: str):
    if name in _LAZY:
        import importlib

        from .workflow.api import LAZY

        module, attr = LAZY[name]
        value = getattr(importlib.import_module(module), attr)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'fogbayes' has no attribute {name!r}")
