"""Numba, with fogbayes's compiled-function cache kept out of the installed package.

Registers a cache locator for fogbayes sources: :func:`fogbayes_cache_dir` ``/numba``, else a
per-user temporary folder, never ``__pycache__`` in the package. Fogbayes modules import
``numba`` from here, compile generated source with :func:`njit_source` (cached on disk like a
module's functions) and spread rows over the cores with :func:`over_rows`.
"""

from __future__ import annotations

import hashlib
import importlib.util
import os
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numba
import numpy as np
from numba.core import caching

from .._config import fogbayes_cache_dir

__all__ = ["fogbayes_cache_dir", "njit_source", "numba", "over_rows"]

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


def _source_file(text: str) -> Path | None:
    """``text`` as a file named by its hash under a writable cache folder (written once, so
    its time stamp, which Numba's cache index checks, never changes), or None."""
    name = f"loop_{hashlib.sha256(text.encode()).hexdigest()[:24]}.py"
    for root in FogbayesCacheLocator._roots:
        folder = root() / "numba_src"
        path = folder / name
        try:
            if not path.exists():
                folder.mkdir(parents=True, exist_ok=True)
                tmp = folder / f".{name}.{os.getpid()}.tmp"
                tmp.write_text(text)
                if not path.exists():  # another process may have written it meanwhile
                    os.replace(tmp, path)
                else:
                    tmp.unlink()
            return path
        except OSError:
            continue
    return None


def njit_source(text: str, name: str = "loop", space: dict | None = None, **options):
    """``numba.njit(**options)`` of function ``name`` defined by the generated source ``text``.

    Numba caches only functions defined in files, so the source is written once to the cache
    folder (named by its hash) and imported from there with ``cache=True``: a later process
    loads the machine code instead of compiling it again (seconds per loop). ``space``: the
    names the source uses (e.g. ``np``, ``prange``). Without a writable folder the source is
    compiled in memory, as before.
    """
    path = _source_file(text)
    if path is not None:
        try:
            spec = importlib.util.spec_from_file_location(path.stem, path)
            module = sys.modules.get(path.stem)
            if module is None:  # Numba's cached code looks its module up by name
                module = importlib.util.module_from_spec(spec)
                module.__dict__.update(space or {})
                spec.loader.exec_module(module)
                sys.modules[path.stem] = module
            return numba.njit(cache=True, **options)(getattr(module, name))
        except OSError:
            pass
    namespace = dict(space or {})
    exec(text, namespace)  # noqa: S102 -- our own generated arithmetic, no input text
    return numba.njit(**options)(namespace[name])


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
