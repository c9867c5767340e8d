"""Numba, with fogbayes's compiled-function cache kept out of the installed package.

Numba's ``cache=True`` writes machine code into ``__pycache__`` beside the source file by
default. For an installed package that is ``site-packages/fogbayes/*/__pycache__``: files
pip did not install and does not remove. After ``pip install .`` then ``pip install -e .``
those leftover folders made ``site-packages/fogbayes`` a namespace package that shadowed the
editable install (``import fogbayes`` then ran no ``__init__``: float32 JAX, broken CLI).

Importing numba through this module registers a cache locator, ahead of Numba's own, that
puts the cache of every function defined in a fogbayes source file under
:func:`fogbayes_cache_dir` ``/numba``. If that folder cannot be written, the locator uses a
per-user folder in the system's temporary directory; it never falls through to the in-tree
locator, so nothing is ever written into the package (with neither folder writable it
uses Numba's own per-user cache folder).

Every fogbayes module that compiles with Numba imports ``numba`` from here.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

import numba
from numba.core import caching

from ._config import fogbayes_cache_dir

__all__ = ["fogbayes_cache_dir", "numba"]

_PACKAGE = Path(__file__).resolve().parent

# Numba renamed its locators (``_UserProvidedCacheLocator`` -> ``UserProvidedCacheLocator``).
_Base = getattr(caching, "UserProvidedCacheLocator", None) or caching._UserProvidedCacheLocator


def _is_fogbayes_source(py_file: str) -> bool:
    try:
        return Path(py_file).resolve().is_relative_to(_PACKAGE)
    except (OSError, ValueError):
        return False


class FogbayesCacheLocator(_Base):
    """Cache of a fogbayes function: the user's cache folder, never the package folder."""

    _roots = (lambda: fogbayes_cache_dir() / "numba",
              lambda: Path(tempfile.gettempdir()) / f"fogbayes-numba-{os.getuid()}")

    def __init__(self, py_func, py_file, root: Path | None = None):
        self._py_file = py_file
        self._lineno = py_func.__code__.co_firstlineno
        root = root if root is not None else self._roots[0]()
        self._cache_path = str(root / self.get_suitable_cache_subpath(py_file))

    def get_cache_path(self):
        return self._cache_path

    @classmethod
    def from_function(cls, py_func, py_file):
        if not _is_fogbayes_source(py_file):
            return None  # not ours: Numba's own locators decide
        for root in cls._roots:
            locator = cls(py_func, py_file, root())
            try:
                locator.ensure_cache_path()
                return locator
            except OSError:
                continue
        # No writable folder of ours: Numba's per-user folder, still never the package's.
        user_wide = getattr(caching, "UserWideCacheLocator", None) or caching._UserWideCacheLocator
        return user_wide.from_function(py_func, py_file)


_Impl = getattr(caching, "CacheImpl", None) or caching._CacheImpl
if FogbayesCacheLocator not in _Impl._locator_classes:
    _Impl._locator_classes.insert(0, FogbayesCacheLocator)
