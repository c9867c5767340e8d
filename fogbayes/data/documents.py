"""Fit documents: the versioned schema of what ``fogbayes fit --json`` writes, checked on read.

Documents carry ``"schema": "fogbayes.fit/1"``; readers go through :func:`read_fit_document` /
:func:`validate_fit_document`, which raise a :class:`FitDocumentError` naming document and key
path for: another or newer schema, a loop document or another kind fogbayes writes (named for
what it is, :mod:`~fogbayes.data.doc_kinds`), depth beyond :data:`MAX_DEPTH`, NaN/inf,
unknown model or keys, missing keys, wrong types, and each model's shapes and ranges (shared
rules :mod:`~fogbayes.data.doc_models`, bounds :mod:`~fogbayes.data.doc_rules`, family rules
:data:`MODEL_CHECKS`).
"""


from __future__ import annotations

from pathlib import Path
from typing import Any

from ..errors import UnitError
from .axes_doc import AXES_KEYS, AXES_SCHEMA, is_axes_document
from .doc_kinds import CALIBRATION, FIT, refuse_other_kind
from .doc_models import _allan, _arma, _check_schema, _scan, check_basis
from .json_file import read_json_file
from .doc_rules import (
    COMPENSATING,
    FIT_SCHEMA,
    MAX_DEPTH,
    TOP_LEVEL_KEYS,
    FitDocumentError,
    _Checker,
    _kind,
    is_loop_document,
)

#: model -> its document rules: a function, or "module:function" of a family's package
#: (imported when a document of that model is checked; the data layer names, never imports,
#: the families above it)
MODEL_CHECKS = {"bias-t": "fogbayes.thermal.document:check_document",
                "thermal": "fogbayes.thermal.document:check_document",
                "composite": "fogbayes.composite.document:check_document",
                "allan": _allan, "arma": _arma}
#: the validator of loop documents (the loop package's own rules)
LOOP_CHECK = "fogbayes.loop.calibration_doc:validate_loop_document"


def _resolve(check):
    """A check function from :data:`MODEL_CHECKS` / :data:`LOOP_CHECK`."""
    if callable(check):
        return check
    import importlib

    module, _, name = check.partition(":")
    return getattr(importlib.import_module(module), name)


__all__ = ["COMPENSATING", "FIT_SCHEMA", "FitDocumentError", "agreed_unit", "check_basis",
           "check_channels", "declared_unit", "read_calibration", "read_fit_document",
           "validate_axes_document", "validate_fit_document", "validate_in_memory"]


# -- reading ----------------------------------------------------------------------------
def _load(path: str | Path, what: str = "fit") -> Any:
    """The parsed JSON at ``path``; a :class:`FitDocumentError` naming it if unreadable."""
    return read_json_file(path, f"the {what} document",
                          f"pass the JSON file written by 'fogbayes {what} --json'",
                          error=FitDocumentError)


def read_fit_document(path: str | Path) -> dict:
    """The validated fit document at ``path`` (see the module doc for what is checked)."""
    doc = _load(path)
    validate_fit_document(doc, str(path))
    return doc


def read_calibration(path: str | Path) -> dict:
    """A fit document, a loop document (``fogbayes loop --json``) or a multi-axis document
    (:mod:`fogbayes.data.axes_doc`), validated as what it is.

    Loop documents are checked by :func:`fogbayes.loop.calibration_doc.validate_loop_document`
    (their ``calibration`` must be applicable); anything else as a fit document.
    """
    doc = _load(path)
    refuse_other_kind(doc, str(path), CALIBRATION)  # a summary, plan, prior...: say so
    if is_loop_document(doc):  # the validator (and the loop package) only when needed
        return _resolve(LOOP_CHECK)(doc, str(path))
    if is_axes_document(doc):  # one fit document per axis (fogbayes allan --axis all)
        return validate_axes_document(doc, str(path))
    validate_fit_document(doc, str(path))
    return doc


def validate_axes_document(doc: dict, source: str | None = None) -> dict:
    """Raise a :class:`FitDocumentError` naming ``source`` and the key unless every axis is a
    valid fit document of the document's model (a multi-axis document,
    :mod:`fogbayes.data.axes_doc`); returns ``doc``."""
    if doc.get("schema") != AXES_SCHEMA:
        raise FitDocumentError(f"schema {doc.get('schema')!r} is not one this fogbayes reads "
                               f"({AXES_SCHEMA})", file=source, key="schema",
                               fix="upgrade fogbayes, or write the document again")
    unknown = sorted(set(doc) - AXES_KEYS)
    if unknown:
        raise FitDocumentError(f"unknown key {unknown[0]!r} in a multi-axis document",
                               file=source, key=unknown[0],
                               fix="pass the document fogbayes wrote, unchanged")
    axes = doc.get("axes")
    if not isinstance(axes, dict) or not axes:
        raise FitDocumentError("'axes' must map each axis name to its fit document",
                               file=source, key="axes",
                               fix="pass the document fogbayes wrote, unchanged")
    for name, sub in axes.items():
        validate_fit_document(sub, f"{source}[axes.{name}]")
        if sub.get("model") != doc.get("model"):
            raise FitDocumentError(f"axis {name!r} holds a {sub.get('model')!r} fit in a "
                                   f"{doc.get('model')!r} document", file=source,
                                   key=f"axes.{name}.model",
                                   fix="pass the document fogbayes wrote, unchanged")
    return doc


def validate_fit_document(doc: Any, source: str | None = None) -> dict:
    """Raise a :class:`FitDocumentError` naming ``source`` unless ``doc`` is a usable fit
    document of this schema version (or of an earlier, schema-less one); returns ``doc``.

    ``doc`` must hold plain JSON types (pass an in-memory document through
    :func:`fogbayes.support.jsonable.to_jsonable` first, as :func:`validate_in_memory` does).
    """
    v = _Checker(source)
    if not isinstance(doc, dict):
        v.fail(None, f"the document is a JSON {type(doc).__name__}, not an object with a "
                     "'model' key")
    if is_loop_document(doc):
        v.fail(None, "this is a loop document (written by 'fogbayes loop --json'), not a fit "
                     "document", fix="pass the document of 'fogbayes fit --json' here (a loop "
                                     "document goes to 'compensate --params' and "
                                     "'report --loop')")
    refuse_other_kind(doc, source, FIT)
    _check_schema(doc, v)
    _scan(doc, v)
    model = v.get(doc, "model", str)
    if model not in TOP_LEVEL_KEYS:
        v.fail("model", f"unknown model {model!r}", fix=f"use a document of one of "
                                                        f"{', '.join(TOP_LEVEL_KEYS)}")
    unknown = sorted(set(doc) - TOP_LEVEL_KEYS[model])
    if unknown:
        v.fail(unknown[0], f"unknown key in a {model} document of schema {FIT_SCHEMA} "
                           f"(written by a newer fogbayes, or edited)",
               fix="upgrade fogbayes, or remove the key / fit again with this version")
    v.get(doc, "converged", bool, required=False)  # not needed to apply the model
    v.get(doc, "fogbayes_version", str, required=False)
    warnings = v.get(doc, "warnings", list, required=False)
    for i, w in enumerate(warnings or []):
        if not isinstance(w, str):
            v.fail(f"warnings[{i}]", f"is a {_kind(w)}, not a string")
    _resolve(MODEL_CHECKS[model])(doc, v)
    return doc


def validate_in_memory(doc: Any, source: str | None = None) -> None:
    """:func:`validate_fit_document` of a document as a workflow returns it (NumPy scalars,
    tuples): checked on its JSON form, as it would be written."""
    from ..support.jsonable import to_jsonable

    validate_fit_document(to_jsonable(doc), source or "the fit document")



# -- applying a document to a recording -------------------------------------------------
def declared_unit(path: str | Path) -> str | None:
    """The unit a recording file declares (CSV ``# unit:`` line, Parquet/NPZ/npy metadata),
    or None when it declares none or cannot be read here (the loader reports that)."""
    path = Path(path)
    try:
        if path.suffix.lower() == ".csv":
            with open(path, encoding="utf-8", errors="replace") as fh:
                for line in fh:
                    if not line.strip():
                        continue  # blank lines are allowed before the header
                    if not line.startswith("#"):
                        return None
                    key, sep, value = line[1:].partition(":")
                    if sep and key.strip() == "unit":
                        return value.strip() or None
            return None
        from . import column_streams as formats

        scanners = {".npz": formats._scan_npz, ".npy": formats._scan_npy,
                    ".parquet": formats._scan_parquet, ".pq": formats._scan_parquet}
        scan = formats._scan_npy_dir if path.is_dir() else scanners.get(path.suffix.lower())
        if scan is None:
            return None
        unit = scan(path)[2].get("unit")
        return None if unit in (None, "", "None") else str(unit)
    except Exception:  # noqa: BLE001 -- unreadable here: the loader names the problem
        return None


def agreed_unit(doc: dict, doc_source: str, rec_path: str | Path,
                output_unit: str | None) -> str | None:
    """The unit to read ``rec_path`` in when applying the fit document ``doc``.

    The document's unit (``input.unit``), the file's unit line and ``--output-unit`` must
    agree: ``output_unit``, when given, says which is right; otherwise a file that declares
    another unit than the document is an error (reading it in the document's unit would
    scale it wrongly, e.g. by 3600 for deg/s against deg/h). Without a unit line the
    document's unit is used, as before.
    """
    if output_unit:
        return output_unit
    if not isinstance(doc, dict) or doc.get("model") not in COMPENSATING:
        return None
    doc_unit = (doc.get("input") or {}).get("unit")
    declared = declared_unit(rec_path)
    if declared is not None and doc_unit is not None:
        from .units import normalise_unit

        if normalise_unit(declared, file=str(rec_path)) != normalise_unit(doc_unit):
            raise UnitError(
                f"the file's unit line says {declared} but the fit document {doc_source} "
                f"was made on {doc_unit}", file=str(rec_path), column="output",
                fix=f"state which is right with --output-unit (e.g. --output-unit {declared} "
                    f"if the file's line is), or convert the file to {doc_unit}")
    return declared or doc_unit


def check_channels(doc: dict, doc_source: str, rec) -> None:
    """The temperature channels a thermal document names exist in the recording ``rec``."""
    if not isinstance(doc, dict) or doc.get("model") not in ("bias-t", "thermal"):
        return
    spec = (doc.get("params") or {}).get("spec") or {}
    have = list(rec.temperature_names)
    if not have:
        return  # the compensation itself says the recording has no temperature
    wanted = [("temperature", spec.get("temperature") or "")]
    wanted += [("extra", x) for x in spec.get("extra") or ()]
    wanted += [("gradient", x) for x in spec.get("gradient") or ()]
    for key, name in wanted:
        if name and name not in have:
            raise FitDocumentError(
                f"channel {name[:40]!r} is not in {rec.meta.source or 'the recording'} "
                f"(it has {', '.join(have)})", file=doc_source, key=f"params.spec.{key}",
                fix="compensate a recording with the channels the fit was made on, or fit again")

