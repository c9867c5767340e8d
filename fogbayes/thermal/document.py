"""What a bias-t / thermal fit document must hold to be applied (the family's ``check_document``).

Called by :func:`fogbayes.data.documents.validate_fit_document` via
:data:`fogbayes.data.documents.MODEL_CHECKS`: processing, model, scaled basis, coefficients and
covariance, validity range inside the scaled range.
"""

from __future__ import annotations

from ..data.doc_models import _basis, _input, _optional_objects
from ..data.doc_rules import (COEF_LIMIT, COVARIATE_LIMIT, GAP_FACTOR_LIMIT, MAX_ORDER,
                              WINDOW_LIMIT_S, _Checker, _kind)
from .data import Processing
from .model import ThermalSpec, covariate_names, thermal_terms

_PROCESSING = {"mode": ("default", "paper"), "rate_method": ("savgol", "difference", "paper"),
               "outliers": ("pauta", "none")}
_WINDOWS = ("average_s", "temperature_average_s", "rate_window_s")


def check_document(doc: dict, v: _Checker) -> None:
    """Raise through ``v`` unless the bias-t/thermal part of ``doc`` is usable."""
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
