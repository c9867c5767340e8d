"""Run the loop with single-threaded OpenBLAS (what ``threadpoolctl.threadpool_limits(1)`` does).

Idle OpenBLAS threads spin between the loop's small linear-algebra calls and take the cores
XLA needs. The OpenBLAS copies bundled with NumPy and SciPy are set through their
``*_set_num_threads`` entry points; with another BLAS nothing changes (only speed depends on it).
"""

from __future__ import annotations

import ctypes
from contextlib import contextmanager

_SETTERS = ("scipy_openblas_set_num_threads64_", "scipy_openblas_set_num_threads",
            "openblas_set_num_threads64_", "openblas_set_num_threads")
_GETTERS = ("scipy_openblas_get_num_threads64_", "scipy_openblas_get_num_threads",
            "openblas_get_num_threads64_", "openblas_get_num_threads")


def _openblas_libs() -> list[ctypes.CDLL]:
    import scipy.linalg  # noqa: F401  (make sure SciPy's copy is loaded too)

    try:
        with open("/proc/self/maps") as fh:
            paths = {line.split()[-1] for line in fh if "openblas" in line.lower()}
    except OSError:
        return []
    libs = []
    for p in sorted(paths):
        try:
            libs.append(ctypes.CDLL(p))
        except OSError:
            continue
    return libs


def _entry(lib, names):
    for nm in names:
        fn = getattr(lib, nm, None)
        if fn is not None:
            return fn
    return None


@contextmanager
def single_thread_blas():
    """Context manager: OpenBLAS with one thread inside, the previous count restored after."""
    saved = []
    for lib in _openblas_libs():
        get, set_ = _entry(lib, _GETTERS), _entry(lib, _SETTERS)
        if get is None or set_ is None:
            continue
        saved.append((set_, int(get())))
        set_(1)
    try:
        yield
    finally:
        for set_, n in saved:
            set_(n)
