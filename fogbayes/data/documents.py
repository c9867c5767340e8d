"""Fit documents: the versioned schema of what ``fogbayes fit --json`` writes, checked on read.

Every fit document written (``fogbayes fit``, ``batch``, the workflows'
``fit_recording``) starts with ``"schema": "fogbayes.fit/1"``. Every reader
(``compensate --params``, ``report --fit``, batch and stream compensation, the PX4 export's
:func:`fogbayes.export.basis_from_dict`) goes through :func:`read_fit_document` /
:func:`validate_fit_document`, which refuse, with a :class:`FitDocumentError` naming the
document and the key path (``fit.json: key 'params.raw.coef': 2 values for 5 terms. Fix:
...``):

* a schema other than ``fogbayes.fit/<n>``, or a newer one than this version reads;
  documents without ``schema`` (written before it existed) are read if they pass the rest;
* a loop document (``fogbayes loop --json``): a different format;
* nesting deeper than :data:`MAX_DEPTH`, NaN or infinity anywhere (fogbayes writes
  ``null`` for those), values that are no JSON type;
* an unknown model, unknown top-level keys (a newer writer), missing required keys,
  wrong types;
* per model, shapes and ranges: for ``bias-t``/``thermal`` the coefficient count equals the
  number of terms, the exponents are those of ``params.spec`` (each 0..8), the covariance
  is square of that size, centre/scale/valid range are finite and bounded, scales are
  positive (the centred, scaled basis divides by them), every valid range is ordered
  (min <= max) and lies inside the basis range; for ``composite`` the scaled parameter
  count follows from the orders, scales are non-zero, calibrated ranges ordered; for
  ``allan``/``arma`` the arrays the report draws have matching lengths.

Why plain checks and not JSON Schema (``jsonschema``): most rules that matter here relate
fields to each other (counts against terms, exponents against the model spec, ranges
against the basis), which JSON Schema cannot state; its messages would have to be
rewritten into one line with the key path anyway; and it recurses, so a maliciously deep
document needs a guard before it. The checks below are one pass over the document plus a
few lookups, and need no new dependency.

The bounds (:data:`COEF_LIMIT`, :data:`COVARIATE_LIMIT`, ...) are far outside anything
physical; they exist so that a document that passes cannot overflow float64 when applied.
"""

from __future__ import annotations

import json
import math
import re
from pathlib import Path
from typing import Any

from ..errors import FileFormatError, UnitError

#: The schema name and the newest version this fogbayes reads (and writes).
SCHEMA_NAME = "fogbayes.fit"
SCHEMA_VERSION = 1
FIT_SCHEMA = f"{SCHEMA_NAME}/{SCHEMA_VERSION}"

#: Deepest nesting accepted (fogbayes writes at most ~7 levels).
MAX_DEPTH = 32
#: Largest polynomial order / exponent of a thermal model (as ``check_spec``).
MAX_ORDER = 8
#: Largest |value| of a covariate (deg C, deg C/min): centres, scales, valid ranges.
COVARIATE_LIMIT = 1e6
#: Largest |coefficient| in the scaled basis (deg/h; 1e12 deg/h ~ 3e8 deg/s).
COEF_LIMIT = 1e12
#: Largest |value| of the composite model's scaled parameters and scalings.
COMPOSITE_LIMIT = 1e15
#: Longest averaging / derivative window (s) and largest gap factor accepted.
WINDOW_LIMIT_S = 1e5
GAP_FACTOR_LIMIT = 1e12
#: Range of a scale factor (raw units per deg/s; > 0, as the loader requires).
SCALE_FACTOR_RANGE = (1e-12, 1e12)

FIX = "pass the document written by 'fogbayes fit --json' unchanged, or fit again"
_MISSING = object()

#: Top-level keys per model (anything else is refused: a newer writer or an edit).
_COMMON = {"schema", "model", "fogbayes_version", "converged", "warnings"}
TOP_LEVEL_KEYS = {
    "bias-t": _COMMON | {"input", "params", "processing", "outliers", "fit", "metrics",
                         "order_selection", "bayes", "vectorized", "diagnostics"},
    "composite": _COMMON | {"method", "input", "operating_time", "T_nominal", "orders",
                            "params", "noise", "cells", "samples", "calibrated",
                            "classification", "order_selection", "bayes", "compensation",
                            "table", "table_markdown", "residual_rate_rms", "product"},
    "allan": _COMMON | {"sensor_id", "source", "n", "fs", "unit", "input_unit", "ci", "taus",
                        "gaps", "tau", "adev", "adev_low", "adev_high", "edf", "alpha",
                        "n_terms", "fit", "comparison", "params"},
    "arma": _COMMON | {"sign_convention", "statsmodels_equivalent", "unit", "n", "decimate",
                       "sample_rate_hz", "detrend_order", "criterion", "selected",
                       "selected_aic", "selected_bic", "candidates", "params", "whiteness",
                       "residual", "denoise", "acf", "pacf", "bayes"},
}
TOP_LEVEL_KEYS["thermal"] = TOP_LEVEL_KEYS["bias-t"]
#: Models whose document is applied to a recording (their unit must agree with it).
COMPENSATING = ("bias-t", "thermal", "composite")


class FitDocumentError(FileFormatError):
    """A fit document that cannot be used: ``file`` names it, ``key`` the key path."""

    def __init__(self, problem: str, *, file: str | None = None, key: str | None = None,
                 fix: str | None = FIX):
        self.key = key
        shown = None if key is None else " ".join(str(key).split())[:120]  # one line, short
        super().__init__(f"key '{shown}': {problem}" if key else problem, file=file, fix=fix)


# -- reading ----------------------------------------------------------------------------
def read_fit_document(path: str | Path) -> dict:
    """The validated fit document at ``path`` (see the module doc for what is checked)."""
    src = str(path)
    try:
        text = Path(path).read_text(encoding="utf-8")
    except FileNotFoundError:
        raise FitDocumentError("file not found", file=src,
                               fix="check the path of the fit document") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise FitDocumentError(f"cannot read the file ({type(exc).__name__}: {exc})", file=src,
                               fix="pass the JSON file written by 'fogbayes fit --json'") from None
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as exc:
        raise FitDocumentError(f"not valid JSON ({exc.msg} at line {exc.lineno} column "
                               f"{exc.colno})", file=src,
                               fix="pass the JSON file written by 'fogbayes fit --json'") from None
    except (RecursionError, ValueError) as exc:  # nesting beyond the parser's stack; huge ints
        raise FitDocumentError(f"cannot be parsed ({type(exc).__name__}): nested deeper than "
                               f"{MAX_DEPTH} levels or numbers too long", file=src) from None
    validate_fit_document(doc, src)
    return doc


def validate_fit_document(doc: Any, source: str | None = None) -> dict:
    """Raise a :class:`FitDocumentError` naming ``source`` unless ``doc`` is a usable fit
    document of this schema version (or of an earlier, schema-less one); returns ``doc``.

    ``doc`` must hold plain JSON types (pass an in-memory document through
    :func:`fogbayes._json.to_jsonable` first, as :func:`validate_in_memory` does).
    """
    v = _Checker(source)
    if not isinstance(doc, dict):
        v.fail(None, f"the document is a JSON {type(doc).__name__}, not an object with a "
                     "'model' key")
    if "params" not in doc and {"steps", "initial"} <= set(doc):
        v.fail(None, "this is a loop document (written by 'fogbayes loop --json'), not a fit "
                     "document", fix="pass the document of 'fogbayes fit --json' (a loop "
                                     "document goes to 'report --loop'; the loop writes its "
                                     "compensated output itself with --compensated)")
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
    {"bias-t": _thermal, "thermal": _thermal, "composite": _composite, "allan": _allan,
     "arma": _arma}[model](doc, v)
    return doc


def validate_in_memory(doc: Any, source: str | None = None) -> None:
    """:func:`validate_fit_document` of a document as a workflow returns it (NumPy scalars,
    tuples): checked on its JSON form, as it would be written."""
    from .._json import to_jsonable

    validate_fit_document(to_jsonable(doc), source or "the fit document")


# -- the checks -------------------------------------------------------------------------
def _kind(x) -> str:
    if isinstance(x, bool):
        return "boolean"
    if isinstance(x, (int, float)):
        return "number"
    return {str: "string", list: "list", dict: "object", type(None): "null"}.get(type(x),
                                                                               type(x).__name__)


def _join(path: str | None, key) -> str:
    if isinstance(key, int):
        return f"{path or ''}[{key}]"
    return f"{path}.{key}" if path else str(key)


def _is_num(x) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool)


def _is_kind(x, kind) -> bool:
    if kind is float:  # a JSON number: 1 and 1.0 alike
        return _is_num(x)
    if kind is int:
        return isinstance(x, int) and not isinstance(x, bool)
    return isinstance(x, kind)


class _Checker:
    def __init__(self, source: str | None):
        self.source = source

    def fail(self, key: str | None, problem: str, fix: str | None = FIX):
        raise FitDocumentError(problem, file=self.source, key=key, fix=fix)

    def get(self, obj: dict, key: str, kind, *, path: str | None = None, required: bool = True,
            nullable: bool = False):
        """``obj[key]`` of JSON type ``kind`` (a type or tuple); _MISSING or None if allowed."""
        where = path or key
        if key not in obj:
            if required:
                self.fail(where, "is missing (required)")
            return None
        val = obj[key]
        if val is None and nullable:
            return None
        kinds = kind if isinstance(kind, tuple) else (kind,)
        if not any(_is_kind(val, k) for k in kinds):
            want = " or ".join({str: "a string", bool: "true or false", dict: "an object",
                                list: "a list", float: "a number", int: "an integer"}[k]
                               for k in kinds)
            self.fail(where, f"is a {_kind(val)}, not {want}" + (" or null" if nullable else ""))
        return val

    def number(self, obj: dict, key: str, path: str, *, lo=None, hi=None, required=True,
               nullable=False, integer=False, positive=False, nonzero=False, absmax=None):
        val = self.get(obj, key, int if integer else float, path=path, required=required,
                       nullable=nullable)
        if val is None:
            return None
        self.check_value(val, path, lo=lo, hi=hi, positive=positive, nonzero=nonzero,
                         absmax=absmax)
        return val

    def check_value(self, val, path, *, lo=None, hi=None, positive=False, nonzero=False,
                    absmax=None):
        if not math.isfinite(val):
            self.fail(path, "is not a finite number")
        if positive and not val > 0:
            self.fail(path, f"is {val!r}; it must be positive")
        if nonzero and val == 0:
            self.fail(path, "is 0; it must be non-zero")
        if lo is not None and val < lo or hi is not None and val > hi:
            self.fail(path, f"is {val!r}, outside {lo!r} ... {hi!r}")
        if absmax is not None and abs(val) > absmax:
            self.fail(path, f"is {val!r}; |value| above {absmax:g} is not physical")

    def _list(self, obj: dict, key: str, path: str, n: int | None, what: str,
              required: bool) -> list | None:
        vals = self.get(obj, key, list, path=path, required=required)
        if vals is not None and n is not None and len(vals) != n:
            self.fail(path, f"{len(vals)} values for {n} {what}")
        return vals

    def numbers(self, obj: dict, key: str, path: str, *, n: int | None = None, what="terms",
                required=True, nullable_items=False, **bounds) -> list | None:
        vals = self._list(obj, key, path, n, what, required)
        if vals is None:
            return None
        for i, x in enumerate(vals):
            if x is None and nullable_items:
                continue
            if not _is_num(x):
                self.fail(f"{path}[{i}]", f"is a {_kind(x)}, not a number")
            self.check_value(x, f"{path}[{i}]", **bounds)
        return vals

    def strings(self, obj: dict, key: str, path: str, *, n: int | None = None, what="terms",
                required=True) -> list | None:
        vals = self._list(obj, key, path, n, what, required)
        if vals is None:
            return None
        for i, x in enumerate(vals):
            if not isinstance(x, str):
                self.fail(f"{path}[{i}]", f"is a {_kind(x)}, not a string")
        return vals

    def choice(self, obj: dict, key: str, path: str, options, *, required=True):
        val = self.get(obj, key, str, path=path, required=required)
        if val is not None and val not in options:
            self.fail(path, f"is {val!r}, not one of {', '.join(map(repr, options))}")
        return val

    def interval(self, obj: dict, key: str, path: str, *, required=True, absmax=None):
        """A ``[min, max]`` pair of finite numbers with min <= max."""
        vals = self.numbers(obj, key, path, n=2, what="bounds ([min, max])", required=required,
                            absmax=absmax)
        if vals is not None and vals[0] > vals[1]:
            self.fail(path, f"range [{vals[0]!r}, {vals[1]!r}] has min > max (swapped?)")
        return vals

    def only(self, obj: dict, path: str, allowed) -> None:
        bad = sorted(set(obj) - set(allowed))
        if bad:
            self.fail(_join(path, bad[0]), f"unknown key (expected {', '.join(allowed)})")


def _check_schema(doc: dict, v: _Checker) -> None:
    if "schema" not in doc:
        return  # written before the schema field existed: the checks below decide
    schema = doc["schema"]
    if not isinstance(schema, str):
        v.fail("schema", f"is a {_kind(schema)}, not a string like '{FIT_SCHEMA}'")
    m = re.fullmatch(r"([A-Za-z0-9_.\-]+)/(\d{1,9})", schema)
    if m is None or m.group(1) != SCHEMA_NAME:
        v.fail("schema", f"{schema[:60]!r} is not a fit document schema (this fogbayes reads "
                         f"'{FIT_SCHEMA}')", fix="pass the document written by 'fogbayes fit "
                                                 "--json'")
    version = int(m.group(2))
    if version > SCHEMA_VERSION:
        from .. import __version__

        v.fail("schema", f"'{schema}' is newer than this fogbayes {__version__} reads "
                         f"('{FIT_SCHEMA}')",
               fix="upgrade fogbayes, or fit again with this version")
    if version < 1:
        v.fail("schema", f"'{schema}' is no schema version (the first is '{SCHEMA_NAME}/1')")


def _scan(doc: dict, v: _Checker, prefix: str | None = None) -> None:
    """Depth, JSON types and finite numbers everywhere (iterative: no recursion limit)."""
    stack = [(doc, prefix, 1)]
    while stack:
        obj, path, depth = stack.pop()
        if depth > MAX_DEPTH:
            top = ".".join(re.findall(r"[^.\[\]]+", str(path))[:2])
            v.fail(top, f"is nested deeper than {MAX_DEPTH} levels (fogbayes writes ~7)")
        if isinstance(obj, dict):
            for k in reversed(list(obj)):
                if not isinstance(k, str):
                    v.fail(path, f"has a non-string key {k!r}")
                stack.append((obj[k], _join(path, k), depth + 1))
        elif isinstance(obj, list):
            for i in range(len(obj) - 1, -1, -1):
                stack.append((obj[i], _join(path, i), depth + 1))
        elif isinstance(obj, float):
            if not math.isfinite(obj):
                v.fail(path, f"is {obj!r}: fogbayes writes no NaN or infinity (null instead)")
        elif not (obj is None or isinstance(obj, (str, int, bool))):
            v.fail(path, f"holds a {type(obj).__name__}, which is no JSON value")


def _input(doc: dict, v: _Checker) -> None:
    inp = v.get(doc, "input", dict, required=False)
    if inp is None:
        return
    unit = v.get(inp, "unit", str, path="input.unit", required=False, nullable=True)
    if unit is not None:
        from ..units import normalise_unit

        try:
            normalise_unit(unit)
        except UnitError:
            from ..units import KNOWN_UNITS

            v.fail("input.unit", f"unknown unit {unit[:40]!r}",
                   fix=f"use one of {', '.join(KNOWN_UNITS)}")
    sf = v.number(inp, "scale_factor", "input.scale_factor", required=False, nullable=True,
                  positive=True)
    if sf is not None and not SCALE_FACTOR_RANGE[0] <= sf <= SCALE_FACTOR_RANGE[1]:
        v.fail("input.scale_factor", f"is {sf!r}; a scale factor (raw units per deg/s) lies in "
                                     f"{SCALE_FACTOR_RANGE[0]:g} ... {SCALE_FACTOR_RANGE[1]:g}")
    v.number(inp, "n", "input.n", required=False, nullable=True, integer=True, lo=0)
    for key in ("source", "sensor_id"):
        v.get(inp, key, str, path=f"input.{key}", required=False, nullable=True)


def _optional_objects(doc: dict, v: _Checker, keys) -> None:
    for key in keys:
        v.get(doc, key, dict, required=False)


# -- bias-t / thermal -------------------------------------------------------------------
_PROCESSING = {"mode": ("default", "paper"), "rate_method": ("savgol", "difference", "paper"),
               "outliers": ("pauta", "none")}
_WINDOWS = ("average_s", "temperature_average_s", "rate_window_s")


def _thermal(doc: dict, v: _Checker) -> None:
    from ..models.thermal import ThermalSpec, covariate_names, thermal_terms
    from ..workflow._thermal_data import Processing

    _input(doc, v)
    _optional_objects(doc, v, ("outliers", "fit", "metrics", "order_selection", "bayes",
                               "diagnostics"))
    v.get(doc, "vectorized", bool, required=False)
    proc = v.get(doc, "processing", dict)
    v.only(proc, "processing", Processing._fields)
    for key, options in _PROCESSING.items():
        v.choice(proc, key, f"processing.{key}", options, required=False)
    for key in _WINDOWS:
        v.number(proc, key, f"processing.{key}", required=False, positive=True,
                 hi=WINDOW_LIMIT_S)
    v.number(proc, "n_sigma", "processing.n_sigma", required=False, positive=True, hi=1e3)
    v.number(proc, "rate_gap_factor", "processing.rate_gap_factor", required=False,
             nullable=True, positive=True, hi=GAP_FACTOR_LIMIT)

    p = v.get(doc, "params", dict)
    spec = v.get(p, "spec", dict, path="params.spec")
    v.only(spec, "params.spec", ThermalSpec._fields)
    for key in ("t_order", "rate_order", "extra_order"):
        v.number(spec, key, f"params.spec.{key}", required=False, integer=True, lo=0,
                 hi=MAX_ORDER)
    v.get(spec, "cross", bool, path="params.spec.cross", required=False)
    v.get(spec, "temperature", str, path="params.spec.temperature", required=False)
    for key in ("extra", "gradient"):
        v.strings(spec, key, f"params.spec.{key}", required=False)
    if len(spec.get("gradient") or ()) not in (0, 2):
        v.fail("params.spec.gradient", f"has {len(spec['gradient'])} names; it needs two "
                                       "(outer, inner) or none")
    ts = ThermalSpec(**{k: tuple(x) if isinstance(x, list) else x for k, x in spec.items()})
    names, terms = covariate_names(ts), [list(e) for e in thermal_terms(ts)]

    b = v.get(p, "basis", dict, path="params.basis")
    cov_names, exps, centre, scale = _basis(b, v, "params.basis")
    if list(cov_names) != list(names):
        v.fail("params.basis.covariates", f"{cov_names} do not match the model in "
                                          f"'params.spec' (covariates {list(names)})")
    if exps != terms:
        v.fail("params.basis.exponents", f"{exps} do not match the model in 'params.spec' "
                                         f"(exponents {terms})")
    n = len(terms)

    v.numbers(p, "coef", "params.coef", n=n, absmax=COEF_LIMIT)
    cov = v.get(p, "covariance", list, path="params.covariance", required=False)
    if cov is not None:
        if len(cov) != n:
            v.fail("params.covariance", f"{len(cov)} rows for {n} terms (a {n} x {n} matrix)")
        for i in range(n):
            v.numbers({"r": cov[i]}, "r", f"params.covariance[{i}]", n=n,
                      absmax=COEF_LIMIT ** 2)
    v.numbers(p, "stderr", "params.stderr", n=n, required=False, lo=0.0)
    raw = v.get(p, "raw", dict, path="params.raw", required=False)
    if raw is not None:
        v.strings(raw, "terms", "params.raw.terms", n=n, required=False)
        v.numbers(raw, "coef", "params.raw.coef", n=n)
        v.numbers(raw, "stderr", "params.raw.stderr", n=n, required=False, lo=0.0)
        v.get(raw, "form", str, path="params.raw.form", required=False)
    units = v.get(p, "units", dict, path="params.units", required=False)
    for key, u in (units or {}).items():
        if not isinstance(u, str):
            v.fail(f"params.units.{key}", f"is a {_kind(u)}, not a unit name")
    valid = v.get(p, "valid_range", dict, path="params.valid_range", required=False)
    if valid is not None:
        v.only(valid, "params.valid_range", names)
        for c, name in enumerate(names):
            where = f"params.valid_range.{name}"
            lo, hi = v.interval(valid, name, where, absmax=COVARIATE_LIMIT)
            # the basis was scaled to this very range: centre +- scale (1 where constant)
            slack = 1e-6 * scale[c] + 1e-9 * max(1.0, abs(centre[c]))
            if lo < centre[c] - scale[c] - slack or hi > centre[c] + scale[c] + slack:
                v.fail(where, f"[{lo!r}, {hi!r}] lies outside the range the basis was scaled to "
                              f"(centre {centre[c]!r} +- scale {scale[c]!r})")
    v.only(p, "params", ("spec", "basis", "coef", "covariance", "stderr", "raw", "units",
                         "valid_range"))


def _basis(b: dict, v: _Checker, key: str):
    """Structure of a polynomial basis (:func:`fogbayes.export.basis_to_dict`)."""
    cov_names = v.strings(b, "covariates", f"{key}.covariates")
    exps = v.get(b, "exponents", list, path=f"{key}.exponents")
    for k, e in enumerate(exps):
        where = f"{key}.exponents[{k}]"
        if not isinstance(e, list):
            v.fail(where, f"is a {_kind(e)}, not a list of exponents")
        if len(e) != len(cov_names):
            v.fail(where, f"{len(e)} exponents for {len(cov_names)} covariates")
        for c, x in enumerate(e):
            if not (isinstance(x, int) and not isinstance(x, bool)) or not 0 <= x <= MAX_ORDER:
                v.fail(f"{where}[{c}]", f"is {x!r}; an exponent is an integer 0 ... {MAX_ORDER}")
    if len({tuple(e) for e in exps}) != len(exps):
        v.fail(f"{key}.exponents", "lists a term twice")
    nc = len(cov_names)
    v.strings(b, "terms", f"{key}.terms", n=len(exps), required=False)
    centre = v.numbers(b, "centre", f"{key}.centre", n=nc, what="covariates",
                       absmax=COVARIATE_LIMIT)
    scale = v.numbers(b, "scale", f"{key}.scale", n=nc, what="covariates", positive=True,
                      absmax=COVARIATE_LIMIT)
    return cov_names, exps, centre, scale


def check_basis(d: Any, *, source: str | None = None, key: str = "params.basis") -> None:
    """A :class:`FitDocumentError` unless ``d`` is a well-formed basis (finite centres,
    positive scales, exponents 0 ... 8, one per covariate): for readers of a basis alone,
    e.g. :func:`fogbayes.export.basis_from_dict` behind the PX4 export."""
    v = _Checker(source)
    if not isinstance(d, dict):
        v.fail(key, f"is a {_kind(d)}, not an object")
    _scan(d, v, key)
    _basis(d, v, key)


# -- composite --------------------------------------------------------------------------
_SCALING = ("T_ref", "T_scale", "W_scale", "t_scale", "U_ref", "U_scale")


def _composite(doc: dict, v: _Checker) -> None:
    from ..compensate_composite import METHODS
    from ..composite_cells import CONVENTIONS

    _input(doc, v)
    _optional_objects(doc, v, ("noise", "classification", "order_selection", "bayes",
                               "compensation", "product"))
    v.get(doc, "method", str, required=False)
    v.choice(doc, "operating_time", "operating_time", CONVENTIONS, required=False)
    v.number(doc, "T_nominal", "T_nominal", required=False, absmax=COVARIATE_LIMIT)
    o = v.get(doc, "orders", dict)
    s1, s2, u0, u1 = (v.number(o, k, f"orders.{k}", integer=True, lo=0, hi=6)
                      for k in ("s1", "s2", "u0", "u1"))
    n = (s1 + 1) * (s2 + 1) + u0 + 1 + u1 + 1
    p = v.get(doc, "params", dict)
    v.numbers(p, "scaled", "params.scaled", n=n, what=f"parameters of orders {s1},{s2},{u0},{u1}",
              absmax=COMPOSITE_LIMIT)
    v.strings(p, "labels", "params.labels", n=n, what="parameters", required=False)
    sc = v.get(p, "scaling", dict, path="params.scaling")
    v.only(sc, "params.scaling", _SCALING)
    for key in _SCALING:  # the scales are half-ranges / maxima of the fit data: > 0
        v.number(sc, key, f"params.scaling.{key}", absmax=COMPOSITE_LIMIT,
                 positive=key.endswith("_scale"))
    for part in ("raw", "raw_sd", "raw_lo90", "raw_hi90"):
        raw = v.get(p, part, dict, path=f"params.{part}", required=False)
        if raw is None:
            continue
        rows = v.get(raw, "M", list, path=f"params.{part}.M")
        if len(rows) != s1 + 1:
            v.fail(f"params.{part}.M", f"{len(rows)} rows for S1 order {s1} ({s1 + 1} rows)")
        for i, row in enumerate(rows):
            v.numbers({"M": row}, "M", f"params.{part}.M[{i}]", n=s2 + 1,
                      what="columns (S2 order + 1)")
        v.numbers(raw, "c", f"params.{part}.c", n=u0 + 1, what="coefficients (U0 order + 1)")
        v.numbers(raw, "d", f"params.{part}.d", n=u1 + 1, what="coefficients (U1 order + 1)")
    cal = v.get(doc, "calibrated", dict)
    v.interval(cal, "temperature", "calibrated.temperature", absmax=COVARIATE_LIMIT)
    v.interval(cal, "rate", "calibrated.rate", absmax=COMPOSITE_LIMIT)
    _invertible(doc, v, (s1, s2, u0, u1))
    comp = doc.get("compensation")
    if comp is not None:
        v.choice(comp, "method", "compensation.method", METHODS, required=False)
        v.number(comp, "iterations", "compensation.iterations", required=False, integer=True,
                 lo=0, hi=100)
        v.interval(comp, "box_scaled", "compensation.box_scaled", required=False,
                   absmax=COMPOSITE_LIMIT)
        v.interval(comp, "rate_range", "compensation.rate_range", required=False,
                   absmax=COMPOSITE_LIMIT)
    bayes = doc.get("bayes")
    if bayes is not None:
        draws = v.get(bayes, "draws_scaled", list, path="bayes.draws_scaled", required=False)
        for i, row in enumerate(draws or []):
            v.numbers({"d": row}, "d", f"bayes.draws_scaled[{i}]", n=n, what="parameters",
                      absmax=COMPOSITE_LIMIT)
        v.numbers(bayes, "sigma_draws", "bayes.sigma_draws", required=False, lo=0.0)


def _invertible(doc: dict, v: _Checker, orders) -> None:
    """The compensator divides by the small-rate scale factor S_0(T): it must keep one sign
    over the calibrated temperatures (as :func:`fogbayes.compensate_composite.reciprocal_poly`
    requires when the compensator is built)."""
    import numpy as np

    from ..compensate_composite import MethodError, reciprocal_poly
    from ..models.composite import Orders, Scaling, unpack

    p = doc["params"]
    try:
        reciprocal_poly(unpack(np.asarray(p["scaled"], float), Orders(*orders)),
                        tuple(doc["calibrated"]["temperature"]), Scaling(**p["scaling"]))
    except MethodError as exc:
        v.fail("params.scaled", f"these parameters cannot be inverted: {exc.problem}")


# -- noise models (read by the report only) -----------------------------------------------
def _allan(doc: dict, v: _Checker) -> None:
    v.get(doc, "fit", dict)
    _optional_objects(doc, v, ("gaps", "comparison"))
    tau = v.numbers(doc, "tau", "tau", positive=True)
    for key in ("adev", "adev_low", "adev_high", "edf", "alpha", "n_terms"):
        v.numbers(doc, key, key, n=len(tau), what="tau values", required=key == "adev",
                  nullable_items=key != "adev")
    for key in ("unit", "input_unit"):
        v.get(doc, key, str, required=False)
    params = v.get(doc, "params", dict, required=False)
    for key, x in (params or {}).items():
        if not _is_num(x):
            v.fail(f"params.{key}", f"is a {_kind(x)}, not a number")


def _arma(doc: dict, v: _Checker) -> None:
    p = v.get(doc, "params", dict)
    order_p = v.number(p, "p", "params.p", integer=True, lo=0, hi=100)
    order_q = v.number(p, "q", "params.q", integer=True, lo=0, hi=100)
    v.numbers(p, "phi", "params.phi", n=order_p, what="AR coefficients (p)")
    v.numbers(p, "theta", "params.theta", n=order_q, what="MA coefficients (q)")
    v.number(p, "sigma2", "params.sigma2", lo=0.0)
    v.get(doc, "unit", str, required=False)
    v.get(doc, "candidates", list, required=False)


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
        from ..stream import formats

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
        from ..units import normalise_unit

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
