"""Run-time settings of a fleet fit: the cyclic GC paused, NumPy/SciPy's BLAS on one thread.

Full collections and spinning OpenBLAS threads take time from the compiled loops
(benchmarks/RESULTS_batch.md).
"""

from __future__ import annotations

import gc
from contextlib import contextmanager
from functools import lru_cache


@contextmanager
def one_blas_thread():
    """NumPy/SciPy's BLAS on one thread (its matrices here are tiny).

    OpenBLAS threads busy-wait for a while after every call; on a 2-core machine they took
    the cores from the compiled loops that followed (a 16 ms normal-equation pass measured
    27-66 ms after a BLAS call, 16 ms with one BLAS thread)."""
    with _controller().limit(limits=1, user_api="blas"):
        yield


@lru_cache(maxsize=1)
def _controller():
    from threadpoolctl import ThreadpoolController

    return ThreadpoolController()


@contextmanager
def cyclic_gc_paused():
    """Pause Python's cyclic garbage collector (reference counting still frees everything).

    A fleet fit allocates ~10^5 small containers (segments, layouts, documents); each 700
    allocations trigger a collection and the older generations' scans grow with the heap:
    ~0.1 s per 1 000 sensors (measured) for structures that hold no reference cycles.
    """
    was = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if was:
            gc.enable()
