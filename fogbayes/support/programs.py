"""fogbayes's compiled programs, and a bound on the memory maps their machine code holds.

XLA:CPU (jax 0.9) builds every kernel of a program as an object of its own and keeps three
anonymous memory maps per kernel (code, read-only data, data) for as long as the program is
cached: a small program holds ~6 maps, an ARMA fit (L-BFGS, line search, Hessian) ~1 200-
1 450 (docs/CONTRIBUTING.md). A process that compiles many *different* programs (every ARMA
order and sampler, the loop's filters, the Bayesian fits of each family: a long notebook
session, a service, the test suite) passes the kernel's ``vm.max_map_count`` (65 530 by
default) and the next ``mmap`` fails inside LLVM: the process dies (SIGSEGV or SIGABRT),
with no Python error to catch. A process repeating the same shapes does not grow.

So fogbayes compiles with :func:`program` (``jax.jit`` with the same options) and keeps
a weak registry of those functions. After one of them compiles, the process's maps are
counted; past :data:`MAP_SHARE` of the kernel's limit, the compiled code of every *other*
fogbayes program is dropped (``clear_cache``): their next call traces again and reads the
persistent program cache (:mod:`fogbayes._config`) or compiles. Programs of the user's own,
and JAX's, are left alone. The check costs a read of ``/proc/self/maps`` after a
compilation only (milliseconds, against seconds of compiling); off Linux there is no count
and nothing is dropped.

Maps held outside fogbayes's programs (JAX's and NumPyro's small programs, the user's) are
not given back by a release. So the next release waits until the count has grown by
:data:`REGROW_SHARE` of the limit above what the last one left (never past
:data:`CEILING_SHARE`): a process whose own maps alone sit past the limit does not drop and
recompile fogbayes's programs after every compilation. Such a process is told once, by a
``RuntimeWarning``, that it is nearing the kernel's limit and what frees it.
"""

from __future__ import annotations

import functools
import gc
import warnings
import weakref

from .lazy import lazy_module

jax = lazy_module("jax")  # imported by the first program built, not by this module

#: share of ``vm.max_map_count`` past which fogbayes drops its other compiled programs
MAP_SHARE = 0.5
#: growth (share of ``vm.max_map_count``) above the maps a release left before the next one
REGROW_SHARE = 0.125
#: share of ``vm.max_map_count`` past which a compilation always releases
CEILING_SHARE = 0.85
#: the Linux default of ``vm.max_map_count``, used where /proc/sys cannot be read
DEFAULT_MAX_MAP_COUNT = 65_530

_registry: weakref.WeakSet = weakref.WeakSet()
_released = {"times": 0, "left": 0, "warned": False}


def memory_maps() -> int:
    """Memory maps this process holds (lines of ``/proc/self/maps``; 0 off Linux)."""
    try:
        with open("/proc/self/maps", "rb") as f:
            return sum(1 for _ in f)
    except OSError:
        return 0


@functools.lru_cache(maxsize=1)
def max_map_count() -> int:
    """The kernel's limit on one process's memory maps."""
    try:
        with open("/proc/sys/vm/max_map_count") as f:
            return int(f.read().strip())
    except (OSError, ValueError):
        return DEFAULT_MAX_MAP_COUNT


def map_limit() -> int:
    """Maps past which :func:`release_programs` runs after a compilation."""
    return int(MAP_SHARE * max_map_count())


def release_threshold() -> int:
    """Maps past which the next compilation of a fogbayes program releases the others:
    the limit, or the maps the last release left plus :data:`REGROW_SHARE` of the
    kernel's limit where that is higher, and at most :data:`CEILING_SHARE` of it."""
    top = max_map_count()
    regrown = _released["left"] + int(REGROW_SHARE * top)
    return min(max(map_limit(), regrown), int(CEILING_SHARE * top))


def release_programs(keep: object = None) -> int:
    """Drop the compiled code of every fogbayes program but ``keep``; returns how many
    programs held compiled code."""
    dropped = 0
    for prog in list(_registry):
        if prog is not keep and prog.jitted._cache_size():
            prog.jitted.clear_cache()
            dropped += 1
    gc.collect()  # executables are freed with their last reference
    _released["times"] += 1
    _released["left"] = left = memory_maps()
    if left > map_limit() and not _released["warned"]:
        _released["warned"] = True
        warnings.warn(
            f"this process holds {left} memory maps after fogbayes dropped its own compiled "
            f"programs, past half of the kernel's limit (vm.max_map_count = "
            f"{max_map_count()}); at the limit the process dies. Most are other compiled "
            "JAX programs: jax.clear_caches() frees them, or raise vm.max_map_count.",
            RuntimeWarning, stacklevel=3)
    return dropped


def releases() -> int:
    """How often this process has dropped fogbayes's programs (for tests and reports)."""
    return _released["times"]


class Program:
    """A ``jax.jit`` function that, when a call compiled, keeps the process's maps bounded.

    Attributes other than the call (``lower``, ``trace``, ``clear_cache``, ...) are the
    jitted function's."""

    def __init__(self, fun, **jit_options):
        self.jitted = jax.jit(fun, **jit_options)
        functools.update_wrapper(self, fun)
        _registry.add(self)

    def __call__(self, *args, **kwargs):
        jitted = self.jitted
        cached = jitted._cache_size()
        out = jitted(*args, **kwargs)
        if jitted._cache_size() > cached and memory_maps() > release_threshold():
            release_programs(keep=self)
        return out

    def __getattr__(self, name):  # only for names the instance lacks
        jitted = self.__dict__.get("jitted")
        if jitted is None:  # half-built (copy, unpickling): no attributes to forward yet
            raise AttributeError(name)
        return getattr(jitted, name)

    def __get__(self, obj, objtype=None):  # as a method, like a plain function
        return self if obj is None else functools.partial(self, obj)


def program(fun=None, **jit_options):
    """``jax.jit(fun, **jit_options)`` registered with the map bound above; usable as a
    decorator, with or without options (``@partial(program, static_argnames=...)``)."""
    if fun is None:
        return functools.partial(program, **jit_options)
    return Program(fun, **jit_options)
