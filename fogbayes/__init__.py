"""fogbayes: probabilistic modelling of fiber-optic-gyroscope errors.

Importing fogbayes turns on JAX float64 (see :mod:`fogbayes._config`).
"""

from . import _config  # noqa: F401  (float64 on before any JAX array is made)
from .data import Metadata, Recording, load, save
from .errors import FogbayesError

__version__ = "0.1.0"
__all__ = ["FogbayesError", "Metadata", "Recording", "load", "save", "__version__"]
