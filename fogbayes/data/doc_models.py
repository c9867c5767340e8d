"""Per-model checks of fit documents (bias-t/thermal, composite, allan, arma) and the
whole-document scans; :func:`fogbayes.data.documents.validate_fit_document` calls them."""

from __future__ import annotations

import math
import re
from typing import Any

from ..errors import UnitError
from .doc_rules import (
    COEF_LIMIT,
    COMPOSITE_LIMIT,
    COVARIATE_LIMIT,
    FIT_SCHEMA,
    GAP_FACTOR_LIMIT,
    MAX_DEPTH,
    MAX_ORDER,
    SCALE_FACTOR_RANGE,
    SCHEMA_NAME,
    SCHEMA_VERSION,
    WINDOW_LIMIT_S,
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
    from ..thermal.model import ThermalSpec, covariate_names, thermal_terms
    from ..thermal.data import Processing

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
    from ..composite.compensate import METHODS
    from ..composite.cells import CONVENTIONS

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
    over the calibrated temperatures (as :func:`fogbayes.composite.compensate.reciprocal_poly`
    requires when the compensator is built)."""
    import numpy as np

    from ..composite.compensate import MethodError, reciprocal_poly
    from ..composite.model import Orders, Scaling, unpack

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


