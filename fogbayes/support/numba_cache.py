"""Numba, with fogbayes's compiled-function cache kept out of the installed package.

Registers a cache locator for fogbayes sources: :func:`fogbayes_cache_dir` ``/numba``, else a
per-user temporary folder, never ``__pycache__`` in the package. Fogbayes modules import
``numba`` from here and spread rows over the cores with :func:`over_rows`.
"""

from __future__ import annotations

import os
import tempfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numba
import numpy as np
from numba.core import caching

from .._config import fogbayes_cache_dir

__all__ = ["fogbayes_cache_dir", "numba", "over_rows"]

_PACKAGE = Path(__file__).resolve().parent.parent  # fogbayes/, this file is in support/

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


def over_rows(kernel, n_rows: int, *args, min_rows: int = 2) -> None:
    """``kernel(r0, r1, *args)`` over contiguous ranges of ``n_rows`` rows, one range per
    Numba thread (``NUMBA_NUM_THREADS``), or one call for fewer than ``min_rows`` rows.

    ``kernel`` is a ``nogil`` loop over its rows ``range(r0, r1)`` that writes only their
    outputs, so the threads run at once. fogbayes' loops over sensors are written this way
    rather than as ``prange`` loops: the same speed, but Numba's parallel passes made a
    first compilation ~3x longer (``fogbayes/batch/kernels.py``: 29 s -> 10 s for six
    kernels). A kernel's exception is raised here.
    """
    n = max(1, min(numba.get_num_threads(), n_rows)) if n_rows >= min_rows else 1
    if n == 1:
        kernel(0, n_rows, *args)
        return
    edges = np.linspace(0, n_rows, n + 1).astype(np.int64)
    with ThreadPoolExecutor(n) as pool:
        jobs = [pool.submit(kernel, int(edges[k]), int(edges[k + 1]), *args) for k in range(n)]
        for job in jobs:
            job.result()
