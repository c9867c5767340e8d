"""Notebooks that read measured data skip, as the tests do, when the data are absent.

A notebook lists the folders of ``shared/data/measured/`` it reads in its metadata
(``"fogbayes": {"measured": [...]}``). Without them the notebook is skipped with the reason
and the place to get them; under CI (``CI`` set) it runs anyway, so it fails loudly, as
the measured-data tests do. The data are licensed separately and never copied here.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest

HERE = Path(__file__).resolve().parent
SHARED = Path(os.environ.get("FOGBAYES_SHARED", HERE.parents[1] / "shared"))


def measured_folders(notebook: Path) -> list[str]:
    """The measured-data folders a notebook declares in its metadata."""
    meta = json.loads(notebook.read_text(encoding="utf-8")).get("metadata", {})
    return list(meta.get("fogbayes", {}).get("measured", []))


def pytest_collection_modifyitems(config, items):
    for item in items:
        path = Path(str(getattr(item, "path", item.fspath)))
        if path.suffix != ".ipynb" or path.parent != HERE or os.environ.get("CI"):
            continue
        missing = [d for d in measured_folders(path)
                   if not (SHARED / "data" / "measured" / d).is_dir()]
        if missing:
            item.add_marker(pytest.mark.skip(
                reason=f"measured data {missing} not found under {SHARED / 'data' / 'measured'} "
                       "(README.md, 'Measured data'; set FOGBAYES_SHARED)"))
