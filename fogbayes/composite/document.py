"""What a composite fit document must hold to be applied (the family's ``check_document``).

Called by :func:`fogbayes.data.documents.validate_fit_document` via
:data:`fogbayes.data.documents.MODEL_CHECKS`: orders and parameter count, scaling, raw
matrices, ranges, compensation settings, draws, invertibility over the temperatures.
"""

from __future__ import annotations

import numpy as np

from ..data.doc_models import _input, _optional_objects
from ..data.doc_rules import COMPOSITE_LIMIT, COVARIATE_LIMIT, _Checker
from ..preprocess.operating_time import CONVENTIONS
from .compensate import METHODS, MethodError, reciprocal_poly
from .model import Orders, Scaling, unpack

_SCALING = ("T_ref", "T_scale", "W_scale", "t_scale", "U_ref", "U_scale")


def check_document(doc: dict, v: _Checker) -> None:
    """Raise through ``v`` unless the composite part of ``doc`` is usable."""
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
    p = doc["params"]
    try:
        reciprocal_poly(unpack(np.asarray(p["scaled"], float), Orders(*orders)),
                        tuple(doc["calibrated"]["temperature"]), Scaling(**p["scaling"]))
    except MethodError as exc:
        v.fail("params.scaled", f"these parameters cannot be inverted: {exc.problem}")
