"""Packages only some users need: ``fogbayes[parquet]`` (pyarrow), ``fogbayes[dask]``, ``fogbayes[all]``.

Imported through :func:`require` inside the function that needs it; missing, it raises a
:class:`~fogbayes.errors.MissingExtraError` (one ``fogbayes: error:`` line, exit 2).
"""

from __future__ import annotations

import importlib
from types import ModuleType

from ..errors import MissingExtraError

__all__ = ["PARQUET", "DASK", "require"]

#: (extra, what needs it) of each optional feature: ``require("pyarrow.parquet", *PARQUET)``
PARQUET = ("parquet", "Parquet files")
DASK = ("dask", "Batch runs with --engine dask")


def require(module: str, extra: str, what: str) -> ModuleType:
    """Import and return ``module``, or raise :class:`MissingExtraError` naming ``extra``.

    Args:
        module: the dotted module name, e.g. ``"pyarrow.parquet"``.
        extra: the fogbayes extra that installs it, e.g. ``"parquet"``.
        what: what needs it, the (plural) subject of the message, e.g. ``"Parquet files"``.

    A package that is installed but fails to import (a broken or mismatched build, a
    dependency of its own missing) is reported as such, with the reinstall command; the
    original ImportError is kept as the cause.
    """
    try:
        return importlib.import_module(module)
    except ImportError as exc:
        package = module.split(".")[0]
        fix = f"pip install 'fogbayes[{extra}]'"
        missing = getattr(exc, "name", None)
        if isinstance(exc, ModuleNotFoundError) and missing is not None \
                and module.startswith(missing) and missing.split(".")[0] == package:
            raise MissingExtraError(f"{what} need {package}, which is not installed",
                                    fix=fix) from None
        reason = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise MissingExtraError(f"{what} need {package}, which is installed but cannot be "
                                f"imported ({reason})",
                                fix=f"pip install --force-reinstall '{package}' or {fix}") from exc
