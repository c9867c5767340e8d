"""What a recording's metadata values, the loaders' arguments and its numbers may be.

Metadata :func:`meta_float`, :func:`meta_text`, :func:`meta_unit` (empty values refused);
arguments :func:`time_divisor`, :func:`finite`; plausibility :func:`check_plausible`
(:func:`check_time_step`, :func:`check_temperature`): sample rate 1e-4 Hz ... 1 MHz, temperature
-100 ... 200 deg C, metadata sample rate consistent with the time stamps.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import ArgumentError, ImplausibleValueError, MetadataError, UnitError
from ._read import Table

#: Divisors that turn a time column into seconds (``--time-unit``, ``time_unit=``).
TIME_UNITS = {"s": 1.0, "ms": 1e3, "us": 1e6, "µs": 1e6, "ns": 1e9}
#: Plausible sample rates (Hz) and temperatures (deg C) of a gyro recording.
RATE_RANGE = (1e-4, 1e6)
TEMPERATURE_RANGE = (-100.0, 200.0)
#: A metadata sample rate may differ from the median time step by at most this factor.
RATE_TOLERANCE = 1.5

_NONE = ("", "None", "none", "null")
#: what a value of each metadata key looks like, for the fix of a blank ``# key:`` line
_EXAMPLES = {"unit": "deg/h", "sensor_id": "FOG-0070", "sample_rate": "10",
             "scale_factor": "1.0", "temperatures": "temperature,temperature_2"}


def refuse_blank(table: Table, key: str, src: str) -> None:
    """A ``# key:`` line of a CSV file with nothing after the colon is a value forgotten,
    not "no value": refused, naming the file and its line (other formats store no lines)."""
    v, line = table.meta.get(key), table.meta_lines.get(key)
    if line and isinstance(v, str) and not v.strip():
        raise MetadataError(f"'# {key}:' has no value", file=src, line=line,
                            fix=f"write the value, e.g. '# {key}: {_EXAMPLES.get(key, '...')}', "
                                "or delete the line")


# -- metadata values -------------------------------------------------------------------
def meta_float(table: Table, key: str, src: str, *, what: str) -> float | None:
    """A metadata number that must be finite and > 0 (None when absent)."""
    refuse_blank(table, key, src)
    v = table.meta.get(key)
    if v is None or (isinstance(v, str) and v.strip() in _NONE):
        return None
    line = table.meta_lines.get(key)
    fix = (f"write a plain number ({what}), e.g. '# {key}: 10', or delete the line" if line
           else f"store '{key}' as a plain number ({what})")
    if isinstance(v, bool) or not isinstance(v, (int, float, str)):
        raise MetadataError(f"metadata '{key}' is {v!r} ({type(v).__name__}), not a number",
                            file=src, line=line, fix=fix)
    try:
        x = float(v)
    except ValueError:
        raise MetadataError(f"metadata '{key}' is {v!r}, not a number", file=src, line=line,
                            fix=fix) from None
    if not math.isfinite(x) or x <= 0:
        raise MetadataError(f"metadata '{key}' is {v!r}; it must be a finite number > 0",
                            file=src, line=line, fix=fix)
    return x


def meta_text(table: Table, key: str, src: str) -> str | None:
    """A metadata string (numbers are accepted as text; lists and objects are not)."""
    refuse_blank(table, key, src)
    v = table.meta.get(key)
    if v is None:
        return None
    if isinstance(v, bool) or not isinstance(v, (str, int, float)):
        raise MetadataError(f"metadata '{key}' is {v!r} ({type(v).__name__}), not text",
                            file=src, line=table.meta_lines.get(key),
                            fix=f"store '{key}' as a string")
    return str(v).strip()


def meta_unit(table: Table, src: str) -> str:
    """The file's output unit (default deg/h), checked against the known units."""
    from .units import KNOWN_UNITS, normalise_unit

    v = meta_text(table, "unit", src)
    if v in (None, *_NONE):
        return "deg/h"
    try:
        return normalise_unit(v)
    except UnitError:
        raise UnitError(f"unknown output unit {v!r} in the file's metadata 'unit'", file=src,
                        line=table.meta_lines.get("unit"),
                        fix=f"use one of {', '.join(KNOWN_UNITS)}, or override it with "
                            "--output-unit (unit= in fogbayes.load)") from None


# -- arguments -------------------------------------------------------------------------
def time_divisor(time_unit: str) -> float:
    """Seconds per ``time_unit`` as a divisor (``ms`` -> 1000)."""
    div = TIME_UNITS.get(str(time_unit).strip())
    if div is None:
        raise ArgumentError(f"unknown time unit {time_unit!r}", column="--time-unit",
                            fix="use s, ms, us or ns (time_unit= in fogbayes.load)")
    return div


def finite(value, name: str, *, nonzero: bool = False, positive: bool = False) -> float:
    """An argument that must be a finite number (and non-zero / > 0)."""
    try:
        x = float(value)
    except (TypeError, ValueError):
        x = float("nan")
    if not math.isfinite(x) or (nonzero and x == 0) or (positive and x <= 0):
        need = "> 0" if positive else "non-zero" if nonzero else "finite"
        raise ArgumentError(f"{name} is {value!r}; it must be a finite number, {need}",
                            column=name, fix=f"give {name} a finite number ({need})")
    return x


# -- plausibility ----------------------------------------------------------------------
def check_time_step(t: np.ndarray, *, src: str, column: str) -> float | None:
    """The sample rate 1 / median step of ``t`` (seconds), None for fewer than 2 samples;
    raises when it is outside :data:`RATE_RANGE` (times not in seconds)."""
    if t.size < 2:
        return None
    lo, hi = RATE_RANGE
    med = float(np.median(np.diff(t)))
    fs = 1.0 / med
    if not lo <= fs <= hi:
        raise ImplausibleValueError(
            f"the median time step is {med:.6g} s, a sample rate of {fs:.3g} Hz, outside "
            f"the plausible {lo:g} Hz ... {hi:g} Hz: the times are not in seconds",
            file=src, column=column,
            fix="name the time unit with --time-unit ms, us or ns (time_unit= in "
                "fogbayes.load), or convert the column to seconds")
    return fs


def check_temperature(col: np.ndarray, *, src: str, column: str, first_row: int = 0) -> None:
    """Raise when a temperature (deg C) is outside :data:`TEMPERATURE_RANGE`; the row named is
    ``first_row`` + its index (a chunk's place in the file)."""
    t_lo, t_hi = TEMPERATURE_RANGE
    if col.size == 0 or (col.min() >= t_lo and col.max() <= t_hi):
        return  # two reductions: no mask array on the common path
    bad = np.flatnonzero((col < t_lo) | (col > t_hi))
    if bad.size:
        raise ImplausibleValueError(
            f"{bad.size} value(s) outside {t_lo:g} ... {t_hi:g} deg C (first: "
            f"{col[bad[0]]:g}): raw sensor words or kelvin, not deg C", file=src,
            column=column, row=first_row + int(bad[0]),
            fix="convert the column to deg C, or scale it on load with "
                "--temperature-scale A --temperature-offset B (deg C = A x value + B; "
                "kelvin: --temperature-offset -273.15)")


def check_plausible(rec, *, src: str, time_column: str, table: Table) -> None:
    """Refuse a recording whose numbers are valid but physically implausible."""
    lo, hi = RATE_RANGE
    if rec.n >= 2:
        fs = check_time_step(rec.time, src=src, column=time_column)
        med = 1.0 / fs
        declared = rec.meta.sample_rate
        if declared and not 1 / RATE_TOLERANCE <= declared / fs <= RATE_TOLERANCE:
            raise MetadataError(
                f"metadata 'sample_rate' is {declared:g} Hz but the time stamps step by "
                f"{med:.6g} s ({fs:.6g} Hz)", file=src,
                line=table.meta_lines.get("sample_rate"),
                fix="correct or delete the sample_rate metadata, or check the time unit "
                    "(--time-unit)")
    elif rec.meta.sample_rate and not lo <= rec.meta.sample_rate <= hi:
        raise MetadataError(f"metadata 'sample_rate' is {rec.meta.sample_rate:g} Hz, outside "
                            f"{lo:g} Hz ... {hi:g} Hz", file=src,
                            line=table.meta_lines.get("sample_rate"),
                            fix="correct or delete the sample_rate metadata")
    for j, name in enumerate(rec.temperature_names):
        check_temperature(rec.temperatures[:, j], src=src, column=name)
