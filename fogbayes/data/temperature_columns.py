"""Which columns of a file are its temperature channels when the user names none.

The metadata key ``temperatures`` (a JSON list, written by :func:`fogbayes.data.save`), else
``temperature``, ``temperature_2``, ... in that order.
"""

from __future__ import annotations

import json
import re
from typing import Iterable

from ..errors import MetadataError

TEMP_RE = re.compile(r"^temperature(_\d+)?$")
META_KEY = "temperatures"


def _order(name: str) -> int:
    return 1 if name == "temperature" else int(name.rsplit("_", 1)[1])


def listed(names: Iterable[str]) -> str | None:
    """The ``temperatures`` metadata value for channels ``names`` (None: default names)."""
    names = list(names)
    if all(TEMP_RE.match(n) for n in names):
        return None
    return json.dumps(names)


def temperature_columns(columns: Iterable[str], meta_value, src: str) -> list[str]:
    """The channel columns of a file with ``columns`` and metadata ``temperatures``."""
    columns = list(columns)
    if meta_value is None:
        return sorted((c for c in columns if TEMP_RE.match(c)), key=_order)
    try:
        names = json.loads(meta_value) if isinstance(meta_value, str) else meta_value
    except ValueError:
        names = None
    if not isinstance(names, list) or not all(isinstance(n, str) for n in names):
        raise MetadataError(f"metadata 'temperatures' is {str(meta_value)[:80]!r}, not a JSON "
                            "list of column names", file=src,
                            fix="repair or delete that metadata entry, or name the channels "
                                "with --temperature")
    missing = [n for n in names if n not in columns]
    if missing:
        raise MetadataError(f"metadata 'temperatures' lists column {missing[0]!r}, which the "
                            f"file does not have (it has {columns})", file=src,
                            fix="name the channels with --temperature, or repair the metadata")
    return names
