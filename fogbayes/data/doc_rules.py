"""The rules of fit documents: limits, the error, and the checker the model validators use.

Split from :mod:`fogbayes.data.documents` (the reading API, which the module doc there
describes) and :mod:`fogbayes.data.doc_models` (one validator per model).
"""

from __future__ import annotations

import math

from ..errors import FileFormatError

#: The schema name and the newest version this fogbayes reads (and writes).
SCHEMA_NAME = "fogbayes.fit"
SCHEMA_VERSION = 1
FIT_SCHEMA = f"{SCHEMA_NAME}/{SCHEMA_VERSION}"
#: The loop document's schema (``fogbayes loop --json``, :mod:`fogbayes.loop.calibration`).
LOOP_SCHEMA_NAME = "fogbayes.loop"
LOOP_SCHEMA_VERSION = 1
LOOP_SCHEMA = f"{LOOP_SCHEMA_NAME}/{LOOP_SCHEMA_VERSION}"

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
                        "n_terms", "fit", "comparison", "params", "deviation"},
    "arma": _COMMON | {"sign_convention", "statsmodels_equivalent", "unit", "n", "decimate",
                       "sample_rate_hz", "detrend_order", "criterion", "selected",
                       "selected_aic", "selected_bic", "candidates", "params", "whiteness",
                       "residual", "denoise", "acf", "pacf", "bayes"},
}
TOP_LEVEL_KEYS["thermal"] = TOP_LEVEL_KEYS["bias-t"]
#: Models whose document is applied to a recording (their unit must agree with it).
COMPENSATING = ("bias-t", "thermal", "composite")



def is_loop_document(doc) -> bool:
    """A loop document: a loop schema, or (written before schemas) steps and no params."""
    if not isinstance(doc, dict):
        return False
    schema = doc.get("schema")
    if isinstance(schema, str) and schema.startswith(LOOP_SCHEMA_NAME + "/"):
        return True
    return "params" not in doc and {"steps", "initial"} <= set(doc)


class FitDocumentError(FileFormatError):
    """A fit document that cannot be used: ``file`` names it, ``key`` the key path."""

    def __init__(self, problem: str, *, file: str | None = None, key: str | None = None,
                 fix: str | None = FIX):
        self.key = key
        shown = None if key is None else " ".join(str(key).split())[:120]  # one line, short
        super().__init__(f"key '{shown}': {problem}" if key else problem, file=file, fix=fix)


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


