"""Plain-JSON form of fogbayes results: one sanitiser for every JSON document written.

:func:`to_jsonable`, recursively: NaN/inf -> ``None``; NumPy/JAX scalars and arrays -> Python
numbers and lists; NamedTuples and dataclasses -> dicts; tuples, lists, sets (sorted) -> lists;
keys and paths -> ``str``.
"""

from __future__ import annotations

import dataclasses
import math
import os
from typing import Any

import numpy as np


def to_jsonable(obj: Any) -> Any:
    """``obj`` with every value a plain JSON type (see the module doc)."""
    if isinstance(obj, dict):
        return {str(k): to_jsonable(v) for k, v in obj.items()}
    if isinstance(obj, tuple) and hasattr(obj, "_asdict"):  # NamedTuple: keep the field names
        return to_jsonable(obj._asdict())
    if isinstance(obj, (list, tuple)):
        return [to_jsonable(v) for v in obj]
    if isinstance(obj, (set, frozenset)):
        items = [to_jsonable(v) for v in obj]
        try:
            return sorted(items)
        except TypeError:  # mixed types: any order is as good as another
            return items
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        return {f.name: to_jsonable(getattr(obj, f.name)) for f in dataclasses.fields(obj)}
    if isinstance(obj, (bool, np.bool_)):  # before int: bool is an int subclass
        return bool(obj)
    if isinstance(obj, (int, np.integer)):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        f = float(obj)
        return f if math.isfinite(f) else None
    if isinstance(obj, (str, bytes)):
        return obj
    if isinstance(obj, os.PathLike):
        return os.fspath(obj)
    if hasattr(obj, "tolist"):  # NumPy/JAX arrays and scalars (complex stays as it is)
        return to_jsonable(obj.tolist())
    if hasattr(obj, "_asdict"):  # NamedTuple-like objects that are not tuples
        return to_jsonable(obj._asdict())
    return obj
