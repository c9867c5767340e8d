"""Checks of fit documents shared by every model (schema, whole-document scan, ``input``,
polynomial basis) and the rules of the noise models (allan, arma); the bias-t/thermal and
composite rules live in their families (``fogbayes.thermal.document``,
``fogbayes.composite.document``). :func:`fogbayes.data.documents.validate_fit_document`
calls them."""

from __future__ import annotations

import math
import re
from typing import Any

from ..errors import UnitError
from .doc_rules import (
    COVARIATE_LIMIT,
    FIT_SCHEMA,
    MAX_DEPTH,
    MAX_ORDER,
    SCALE_FACTOR_RANGE,
    SCHEMA_NAME,
    SCHEMA_VERSION,
    _Checker,
    _is_num,
    _join,
    _kind,
)


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
        from .units import normalise_unit

        try:
            normalise_unit(unit)
        except UnitError:
            from .units import KNOWN_UNITS

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


def _basis(b: dict, v: _Checker, key: str):
    """Structure of a polynomial basis (:func:`fogbayes.models.basis_document.basis_to_dict`)."""
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
    e.g. :func:`fogbayes.models.basis_document.basis_from_dict` behind the PX4 export."""
    v = _Checker(source)
    if not isinstance(d, dict):
        v.fail(key, f"is a {_kind(d)}, not an object")
    _scan(d, v, key)
    _basis(d, v, key)


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


