"""A module that loads on first attribute access (JAX, optax: ~0.4 s a CLI call that does
not need them should not pay)."""

from __future__ import annotations

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
