"""fogbayes's compiled programs, and a bound on the memory maps their machine code holds.

XLA:CPU keeps memory maps per kernel; past ``vm.max_map_count`` a process dies in LLVM. Functions
made by :func:`program` (``jax.jit``) are registered weakly; after a compilation, past
:data:`MAP_SHARE` of the limit, the other fogbayes programs' code is dropped (``clear_cache``;
they reload from :mod:`fogbayes._config`'s persistent cache). Releases wait for growth of
:data:`REGROW_SHARE` (never past :data:`CEILING_SHARE`); a ``RuntimeWarning`` says so once. Linux only.
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
        if prog is not keep and "jitted" in prog.__dict__ and prog.jitted._cache_size():
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
        self._fun, self._jit_options = fun, jit_options
        functools.update_wrapper(self, fun)
        _registry.add(self)

    @functools.cached_property
    def jitted(self):
        """``jax.jit`` of the function, made at first use: defining a program imports no
        JAX (~2 s of a command that never runs one)."""
        return jax.jit(self._fun, **self._jit_options)

    def __call__(self, *args, **kwargs):
        jitted = self.jitted
        cached = jitted._cache_size()
        out = jitted(*args, **kwargs)
        if jitted._cache_size() > cached and memory_maps() > release_threshold():
            release_programs(keep=self)
        return out

    def __getattr__(self, name):  # only for names the instance lacks
        if "_fun" not in self.__dict__:  # half-built (copy, unpickling): nothing to forward yet
            raise AttributeError(name)
        return getattr(self.jitted, name)

    def __get__(self, obj, objtype=None):  # as a method, like a plain function
        return self if obj is None else functools.partial(self, obj)


def program(fun=None, **jit_options):
    """``jax.jit(fun, **jit_options)`` registered with the map bound above; usable as a
    decorator, with or without options (``@partial(program, static_argnames=...)``)."""
    if fun is None:
        return functools.partial(program, **jit_options)
    return Program(fun, **jit_options)
