"""Checks of a loop document before its calibration is applied to a recording.

Refused with a :class:`~fogbayes.data.doc_rules.FitDocumentError` naming document and key path:
a non-loop or newer schema, no ``calibration``, unknown kinds, missing or non-finite parameters,
non-positive scales, powers outside 0..8, unknown channels, coefficient or covariance sizes
that do not match the columns; depth, types and NaN as :func:`fogbayes.data.doc_models._scan`.
"""

from __future__ import annotations

import math
import re

from ..data.doc_models import _scan
from ..effects.kinds import KINDS
from ..data.doc_rules import (COEF_LIMIT, LOOP_SCHEMA, LOOP_SCHEMA_NAME, LOOP_SCHEMA_VERSION,
                              MAX_ORDER, FitDocumentError, _Checker, _kind, is_loop_document)

__all__ = ["channel_order", "is_loop_document", "match_channels", "validate_loop_document"]

FIX = "pass the document written by 'fogbayes loop --json' unchanged, or run the loop again"

_CHANNEL_KEYS = ("channel", "a", "b")


class _LoopChecker(_Checker):
    def fail(self, key, problem, fix=FIX):
        raise FitDocumentError(problem, file=self.source, key=key, fix=fix)


def _check_schema(doc: dict, v: _Checker) -> None:
    schema = doc.get("schema")
    if schema is None:
        v.fail("schema", "missing: this loop document was written before loop documents "
                         "carried a calibration", fix="run 'fogbayes loop' again with this "
                                                      "version to get an applicable document")
    m = re.fullmatch(r"([A-Za-z0-9_.\-]+)/(\d{1,9})", str(schema))
    if m is None or m.group(1) != LOOP_SCHEMA_NAME or int(m.group(2)) < 1:
        v.fail("schema", f"{str(schema)[:60]!r} is not a loop document schema (this fogbayes "
                         f"reads '{LOOP_SCHEMA}')")
    if int(m.group(2)) > LOOP_SCHEMA_VERSION:
        from .. import __version__

        v.fail("schema", f"'{schema}' is newer than this fogbayes {__version__} reads "
                         f"('{LOOP_SCHEMA}')", fix="upgrade fogbayes, or run the loop again "
                                                   "with this version")


def _number(v: _Checker, x, key: str, positive: bool = False) -> float:
    if isinstance(x, bool) or not isinstance(x, (int, float)) or not math.isfinite(x):
        v.fail(key, f"is a {_kind(x)}, not a finite number")
    if abs(x) > COEF_LIMIT:
        v.fail(key, f"{x:g} is beyond {COEF_LIMIT:g}")
    if positive and x <= 0:
        v.fail(key, f"is {x:g}; it must be positive (the term's column divides by it)")
    return float(x)


def _terms(cal: dict, v: _Checker, n_channels: int) -> int:
    terms = v.get(cal, "terms", list, path="calibration.terms")
    if not terms:
        v.fail("calibration.terms", "is empty: the model has no term")
    n_cols = 0
    for i, d in enumerate(terms):
        at = f"calibration.terms[{i}]"
        if not isinstance(d, dict):
            v.fail(at, f"is a {_kind(d)}, not an object")
        kind = v.get(d, "kind", str, path=f"{at}.kind")
        if kind not in KINDS:
            v.fail(f"{at}.kind", f"unknown term kind {kind!r} (written by a newer fogbayes, "
                                 "or edited)", fix="upgrade fogbayes, or run the loop again")
        if d.get("applies", "sensor") not in ("sensor", "run"):
            v.fail(f"{at}.applies", f"{d.get('applies')!r} is neither 'sensor' nor 'run'")
        params = v.get(d, "params", dict, path=f"{at}.params")
        for key, rule in KINDS[kind].needs.items():
            pk = f"{at}.params.{key}"
            if key not in params:
                v.fail(pk, "missing")
            x = params[key]
            if rule == "int":
                if isinstance(x, bool) or not isinstance(x, int) or not 0 <= x < n_channels:
                    v.fail(pk, f"{x!r} is not a temperature channel of this document "
                               f"(0..{n_channels - 1})")
            elif rule == "powers":
                if (not isinstance(x, list) or not x or any(
                        isinstance(e, bool) or not isinstance(e, int) or not 0 <= e <= MAX_ORDER
                        for e in x)):
                    v.fail(pk, f"must be a non-empty list of integers 0..{MAX_ORDER}")
            else:
                _number(v, x, pk, positive=rule == "pos")
        if kind == "omega_tpoly" and "wpower" in params:
            w = params["wpower"]
            if isinstance(w, bool) or not isinstance(w, int) or not 1 <= w <= MAX_ORDER:
                v.fail(f"{at}.params.wpower", f"must be an integer 1..{MAX_ORDER}")
        n_cols += KINDS[kind].n_cols(params)
    return n_cols


def validate_loop_document(doc, source: str | None = None) -> dict:
    """Raise a :class:`FitDocumentError` unless ``doc`` is an applicable loop document."""
    v = _LoopChecker(source)
    if not isinstance(doc, dict):
        v.fail(None, f"the document is a JSON {type(doc).__name__}, not an object")
    _check_schema(doc, v)
    if "params" in doc and "calibration" not in doc:
        v.fail("schema", f"says {doc['schema']!r} but the document is a fit document (it has "
                         "'params', no 'calibration'): edited or mixed up")
    _scan(doc, v)
    model = v.get(doc, "model", str)
    if model not in ("bias-t", "thermal", "composite", "allan"):
        v.fail("model", f"unknown model {model!r}")
    cal = doc.get("calibration")
    if not isinstance(cal, dict):
        v.fail("calibration", "missing: this loop document carries no calibration",
               fix="run 'fogbayes loop' again with this version")
    family = v.get(cal, "family", str, path="calibration.family")
    if family not in ("bias", "composite"):
        v.fail("calibration.family", f"{family!r} is neither 'bias' nor 'composite'")
    inp = v.get(doc, "input", dict)
    names = v.get(inp, "temperatures", list, path="input.temperatures")
    if any(not isinstance(x, str) for x in names):
        v.fail("input.temperatures", "must be a list of channel names")
    n_cols = _terms(cal, v, len(names))
    coef = v.get(cal, "coefficients", list, path="calibration.coefficients")
    if len(coef) != n_cols:
        v.fail("calibration.coefficients", f"{len(coef)} values for {n_cols} term columns")
    for i, c in enumerate(coef):
        _number(v, c, f"calibration.coefficients[{i}]")
    covm = cal.get("covariance")
    if covm is not None and (not isinstance(covm, list) or len(covm) != n_cols or any(
            not isinstance(r, list) or len(r) != n_cols for r in covm)):
        v.fail("calibration.covariance", f"must be a {n_cols} x {n_cols} matrix")
    if family == "composite" and not inp.get("input_rate"):
        v.fail("input.input_rate", "a composite calibration needs the input rate")
    return doc


def channel_order(doc: dict, have, source: str | None) -> list[int] | None:
    """Indices of the document's temperature channels among ``have`` (names), in the
    document's order; None to keep the recording's own order.

    A recording with exactly as many channels as the document, under other names, is taken
    in its own order (a renamed column is the common case); otherwise every name the
    document uses must be present.
    """
    from ..data.doc_rules import FitDocumentError as Err

    names = list(doc["input"].get("temperatures") or [])
    have = list(have)
    used = sorted({int(t["params"][k]) for t in doc["calibration"]["terms"]
                   for k in _CHANNEL_KEYS if k in t["params"]})
    if not used:
        return None
    if len(have) <= max(used):
        raise Err(f"the calibration uses {max(used) + 1} temperature channel(s) "
                  f"({', '.join(names[:max(used) + 1])}); {source or 'the recording'} "
                  f"has {len(have)}", file=source, key="input.temperatures",
                  fix="give the channels with --temperature (e.g. --temperature "
                      + " --temperature ".join(names[:max(used) + 1]) + ")")
    if all(n in have for n in names):
        return [have.index(n) for n in names]
    missing = [names[j] for j in used if names[j] not in have]
    if missing and len(have) != len(names):
        raise Err(f"channel {missing[0]!r} of the calibration is not in "
                  f"{source or 'the recording'} (it has {', '.join(have)})",
                  file=source, key="input.temperatures",
                  fix="name the channels with --temperature in the calibration's order")
    return None


def match_channels(doc: dict, rec):
    """``rec`` with its temperature channels in the document's order (:func:`channel_order`)."""
    import numpy as np

    idx = channel_order(doc, rec.temperature_names, rec.meta.source)
    if idx is None:
        return rec
    names = tuple(doc["input"]["temperatures"])
    return rec.replace(temperatures=np.asarray(rec.temperatures)[:, idx], temperature_names=names)
