"""Independent calls side by side in threads, results in order.

For work that spends its time outside the GIL (Numba ``nogil`` kernels, LAPACK): each call
gives what it gives alone, so results do not depend on the thread count. ``FOGBAYES_THREADS``
caps the count (e.g. 1 where several fogbayes processes already share the cores: Dask
workers, the test suite's xdist workers).
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterable
from concurrent.futures import ThreadPoolExecutor


def _workers() -> int:
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    try:
        cap = int(os.environ.get("FOGBAYES_THREADS", "0"))
    except ValueError:
        cap = 0  # not a number: no cap (a thread count only changes speed)
    return max(1, min(cores or 1, cap) if cap > 0 else cores or 1)


#: threads: the cores this process may use, at most ``$FOGBAYES_THREADS``
WORKERS = _workers()


def thread_map(fn: Callable, items: Iterable, *, workers: int | None = None) -> list:
    """``[fn(x) for x in items]`` in up to ``workers`` threads (default :data:`WORKERS`)."""
    items = list(items)
    n = min(len(items), WORKERS if workers is None else workers)
    if n < 2:
        return [fn(x) for x in items]
    with ThreadPoolExecutor(n, thread_name_prefix="fogbayes-map") as pool:
        return list(pool.map(fn, items))
