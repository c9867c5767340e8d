"""A module that loads on first attribute access (JAX, optax: ~0.4 s a CLI call that does
not need them should not pay)."""

from __future__ import annotations

import contextlib
import importlib
import sys
from types import ModuleType


class _LazyModule(ModuleType):
    def __init__(self, name: str):
        super().__init__(name)
        self.__dict__["_target"] = name

    def __getattr__(self, attr: str):
        module = importlib.import_module(self.__dict__["_target"])
        return getattr(module, attr)


def lazy_module(name: str) -> ModuleType:
    """A stand-in for ``import name`` that imports it when an attribute is first used."""
    return _LazyModule(name)


def jax_on_cpu() -> bool:
    """True unless JAX is in use with an accelerator. A caller that never imported JAX gets
    the CPU paths (compiled loops, NumPy) without starting JAX (~0.7 s of a CLI call)."""
    if "jax" not in sys.modules:
        return True
    import jax

    return jax.default_backend() == "cpu"


@contextlib.contextmanager
def host_device():
    """Run the JAX work inside on the CPU, even where an accelerator is JAX's default.

    For latency-bound programs -- a Kalman filter's ``lax.scan`` over a few thousand blocks,
    a NUTS chain's small gradient steps -- where each step is a device kernel launch: on an
    H100 machine the closed loop took 81.6 s with the GPU against 30.5 s on the same
    machine's CPU, with the same result (benchmarks/RESULTS_gpu.md). Large array work
    (compensation, fleet fits, Allan deviations) keeps the default device. Where JAX was
    started without a CPU backend (``JAX_PLATFORMS=cuda``) this does nothing, and so it
    does where JAX has not been imported: what runs inside without JAX (the noise fits'
    compiled loops) needs no device, and a command that never uses JAX does not start it.
    """
    if "jax" not in sys.modules:
        yield
        return
    import jax

    try:
        cpu = jax.devices("cpu")[0]
    except RuntimeError:
        cpu = None
    if cpu is None or jax.default_backend() == "cpu":
        yield
        return
    with jax.default_device(cpu):
        yield
