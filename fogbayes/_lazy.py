"""A module that loads on first attribute access (JAX, optax: ~0.4 s a CLI call that does
not need them should not pay)."""

from __future__ import annotations

import importlib
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
