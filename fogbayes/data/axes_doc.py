"""Multi-axis documents: one fit document per gyro axis, ``fogbayes.axes/1``.

``{"schema", "model", "fogbayes_version", "source", "axes": {name: <fit document>}}`` written by
``fogbayes allan --axis all`` / ``--column``; each entry is checked as a fit document
(:func:`fogbayes.data.documents.validate_axes_document`).
"""

from __future__ import annotations

from typing import Any

AXES_SCHEMA_NAME = "fogbayes.axes"
AXES_SCHEMA = f"{AXES_SCHEMA_NAME}/1"
AXES_KEYS = {"schema", "model", "fogbayes_version", "source", "axes"}


def is_axes_document(doc: Any) -> bool:
    return isinstance(doc, dict) and isinstance(doc.get("schema"), str) and \
        doc["schema"].startswith(AXES_SCHEMA_NAME + "/")


def axes_document(docs: dict[str, dict], *, source: str | None) -> dict:
    """The multi-axis document of per-axis fit documents (all of one model)."""
    from .. import __version__

    models = {d.get("model") for d in docs.values()}
    if len(models) != 1:
        raise ValueError(f"axes of one document must share a model, got {sorted(models)}")
    return {"schema": AXES_SCHEMA, "model": models.pop(), "fogbayes_version": __version__,
            "source": source, "axes": dict(docs)}


def per_axis(doc: dict, source: str | None = None) -> list[tuple[str | None, dict, str | None]]:
    """``[(axis name, fit document, where)]``: each axis of a multi-axis document, or the
    document itself (name None) -- so that readers treat both alike."""
    if not is_axes_document(doc):
        return [(None, doc, source)]
    return [(name, sub, f"{source}[{name}]") for name, sub in doc["axes"].items()]
