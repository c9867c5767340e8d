"""Priors from a gyro datasheet: the ``fogbayes.prior/1`` document, its units and its density.

``fogbayes prior`` turns a sheet's ARW, bias instability and RRW into N (deg/sqrt(h)), B (deg/h)
and K (deg/h^1.5) of :mod:`fogbayes.allan.model` (factors in :data:`UNIT_TABLE`; a sheet's
"bias instability" is the ADEV floor 0.6643 B unless ``bias_instability_is="B"``), keeping the
sheet's own values under ``datasheet``. Used by ``fogbayes allan --bayes --prior`` and
``fogbayes loop --noise-prior`` (:mod:`fogbayes.loop.noise_prior`). Looseness L:
log theta ~ N(log v, s^2), s = ln L / 1.6449, so P(v/L <= theta <= v L) = 0.90.
"""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import NamedTuple

import numpy as np

from ..errors import FogbayesError, UnitError
from ..models.allan_terms import BI_FACTOR, TERMS, UNITS

SCHEMA_NAME = "fogbayes.prior"
SCHEMA_VERSION = 1
SCHEMA = f"{SCHEMA_NAME}/{SCHEMA_VERSION}"
#: z_0.95 of the standard normal: looseness L puts 90 % of the prior in [v / L, v L]
Z90 = 1.6448536269514722
DEFAULT_LOOSENESS = 3.0
#: the datasheet quantities the writer knows -> the canonical term they fix
QUANTITIES = {"ARW": "N", "bias instability": "B", "RRW": "K"}
_DEG_PER_RAD = 180.0 / math.pi
#: per quantity: sheet unit -> factor f, canonical value = f x sheet value (module doc)
UNIT_TABLE = {
    "ARW": {"deg/sqrt(h)": 1.0, "deg/h/sqrt(Hz)": 1.0 / 60.0, "deg/s/sqrt(Hz)": 60.0,
            "deg/sqrt(s)": 60.0, "mdeg/s/sqrt(Hz)": 0.06,
            "rad/s/sqrt(Hz)": 60.0 * _DEG_PER_RAD, "rad/sqrt(s)": 60.0 * _DEG_PER_RAD,
            "mrad/sqrt(h)": 1e-3 * _DEG_PER_RAD},
    "bias instability": {"deg/h": 1.0, "deg/s": 3600.0, "mdeg/s": 3.6,
                         "rad/s": 3600.0 * _DEG_PER_RAD, "urad/s": 3.6e-3 * _DEG_PER_RAD},
    "RRW": {"deg/h/sqrt(h)": 1.0, "deg/h^1.5": 1.0, "deg/h/sqrt(s)": 60.0,
            "deg/s/sqrt(h)": 3600.0, "deg/s/sqrt(s)": 216000.0, "deg/s^1.5": 216000.0,
            "deg/s^2/sqrt(Hz)": 216000.0, "deg/h^2/sqrt(Hz)": 1.0 / 60.0,
            "rad/s/sqrt(s)": 216000.0 * _DEG_PER_RAD,
            "rad/s^2/sqrt(Hz)": 216000.0 * _DEG_PER_RAD},
}
#: what ``bias_instability_is`` may say: the ADEV floor (0.6643 B) or B itself
BI_CONVENTIONS = ("adev-floor", "B")
#: how to write a prior document, for error messages
HOW = ("write it with 'fogbayes prior --arw 0.05 --arw-unit deg/sqrt(h) --bias-instability "
       "0.5 --bias-instability-unit deg/h [--rrw ...] --json PRIOR.json'")


class PriorError(FogbayesError):
    """A datasheet value, unit or prior document that cannot be used."""


def _norm(unit: str) -> str:
    """Spelling-insensitive form of a unit: lower case, no blanks, deg for degree/°, h for
    hr, sqrt(x) for √x, rt(x) and x^0.5, dph/dps for deg/h, deg/s."""
    u = "".join(str(unit).split()).lower()
    u = u.replace("degrees", "deg").replace("degree", "deg").replace("°", "deg")
    u = u.replace("dph", "deg/h").replace("dps", "deg/s").replace("hr", "h")
    u = re.sub(r"√\(?([a-z]+)\)?", r"sqrt(\1)", u)
    u = re.sub(r"(?<![a-z])rt\(", "sqrt(", u)
    u = re.sub(r"([a-z]+)\^(?:0\.5|\(1/2\))", r"sqrt(\1)", u)
    return u


def convert(quantity: str, value: float, unit: str, *,
            bias_instability_is: str = "adev-floor", flag: str | None = None) -> float:
    """A datasheet ``value`` in ``unit`` as the canonical parameter of ``quantity``.

    Example:
        >>> round(convert("ARW", 1.0, "deg/h/sqrt(Hz)") * 60, 12)  # 1/60 deg/sqrt(h)
        1.0
        >>> round(convert("bias instability", 0.6643, "deg/h"), 3)  # ADEV floor -> B
        1.0
    """
    if quantity not in UNIT_TABLE:
        raise PriorError(f"unknown datasheet quantity {quantity!r}", column=flag,
                         fix=f"use one of {', '.join(UNIT_TABLE)}")
    table = UNIT_TABLE[quantity]
    known = {_norm(k): f for k, f in table.items()}
    unit_flag = None if flag is None else f"{flag}-unit"
    if _norm(unit) not in known:
        raise UnitError(f"unknown {quantity} unit {unit!r}", column=unit_flag,
                        fix=f"use one of {', '.join(table)} (convert other units by hand; "
                            "docs/priors.md has the table)")
    x = _positive(value, flag or quantity)
    out = x * known[_norm(unit)]
    if quantity == "bias instability":
        if bias_instability_is not in BI_CONVENTIONS:
            raise PriorError(f"bias instability convention {bias_instability_is!r}",
                             column="--bias-instability-is",
                             fix="use adev-floor (the ADEV minimum, = 0.664 B: the usual "
                                 "datasheet number) or B (the flicker coefficient)")
        if bias_instability_is == "adev-floor":
            out /= BI_FACTOR
    return out


def _positive(value, key: str, file: str | None = None) -> float:
    try:
        x = float(value)
    except (TypeError, ValueError):
        x = math.nan
    if isinstance(value, bool) or not math.isfinite(x) or x <= 0.0:
        raise PriorError(f"{value!r} is not a finite positive number", file=file, field=key,
                         fix="give the datasheet value as a positive number")
    return x


def _looseness(value, key: str, file: str | None = None) -> float:
    try:
        x = float(value)
    except (TypeError, ValueError):
        x = math.nan
    if isinstance(value, bool) or not math.isfinite(x) or x <= 1.0:
        raise PriorError(f"looseness {value!r} must be a finite number > 1", file=file,
                         field=key, fix="give e.g. 3: the true value lies within a factor 3 "
                                         "of the sheet's with 90 % prior probability")
    return x


class TermPrior(NamedTuple):
    """Log-normal prior of one term: median ``value`` (canonical unit), 90 % within a factor
    ``looseness``; ``datasheet`` what the sheet said (value, unit, quantity) or None."""

    value: float
    looseness: float
    datasheet: dict | None = None

    @property
    def sd_log(self) -> float:
        """s = ln(looseness) / z_0.95, the sd of log theta."""
        return math.log(self.looseness) / Z90

    @property
    def range90(self) -> tuple[float, float]:
        """The central 90 % prior interval (value / looseness, value x looseness)."""
        return self.value / self.looseness, self.value * self.looseness


class DatasheetPrior(NamedTuple):
    """A validated prior document: per canonical term (Q, N, B, K, R) a :class:`TermPrior`."""

    terms: dict
    sensor: str | None = None
    source: str = "given"

    def arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(on, mu, sd), each (5,) in the order of TERMS: on = 1 where the sheet gives the
        term, mu = log value, sd = sd of log (1 where off) -- traced sampler arguments."""
        on, mu, sd = np.zeros(5), np.zeros(5), np.ones(5)
        for i, t in enumerate(TERMS):
            if t in self.terms:
                p = self.terms[t]
                on[i], mu[i], sd[i] = 1.0, math.log(p.value), p.sd_log
        return on, mu, sd

    def to_doc(self) -> dict:
        """The ``fogbayes.prior/1`` document (what :func:`validate_prior` reads back)."""
        terms = {}
        for t in TERMS:
            if t in self.terms:
                p = self.terms[t]
                terms[t] = {"value": p.value, "unit": UNITS[t], "looseness": p.looseness,
                            "range90": list(p.range90)}
                if p.datasheet is not None:
                    terms[t]["datasheet"] = dict(p.datasheet)
        return {"schema": SCHEMA, "sensor": self.sensor, "terms": terms}

    def record(self) -> dict:
        """What a fit document records about the prior it used."""
        return {**self.to_doc(), "source": self.source,
                "rule": "log-normal prior on each term the sheet gives: log theta ~ "
                        "N(log value, (ln looseness / 1.645)^2), 90 % within "
                        "[value / looseness, value x looseness]; the other terms keep the "
                        "half-normal prior; terms on the sheet are kept in term selection"}


def log_density(theta, prior: TermPrior):
    """Log density of the log-normal prior at theta > 0 (module doc; scipy's
    ``lognorm(s=sd_log, scale=value).logpdf``)."""
    theta = np.asarray(theta, dtype=float)
    s = prior.sd_log
    z = (np.log(theta) - math.log(prior.value)) / s
    return -0.5 * z**2 - np.log(theta * s) - 0.5 * math.log(2.0 * math.pi)


def build_prior(*, arw=None, arw_unit: str = "deg/sqrt(h)", bias_instability=None,
                bias_instability_unit: str = "deg/h", bias_instability_is: str = "adev-floor",
                rrw=None, rrw_unit: str = "deg/h/sqrt(h)",
                looseness: float = DEFAULT_LOOSENESS, sensor: str | None = None,
                source: str = "datasheet") -> DatasheetPrior:
    """The prior from datasheet values (None = not on the sheet), converted to canonical
    units (module doc); the same ``looseness`` for every term."""
    loose = _looseness(looseness, "--looseness")
    given = (("ARW", arw, arw_unit, "--arw"),
             ("bias instability", bias_instability, bias_instability_unit,
              "--bias-instability"), ("RRW", rrw, rrw_unit, "--rrw"))
    terms = {}
    for quantity, value, unit, flag in given:
        if value is None:
            continue
        canon = convert(quantity, value, unit, bias_instability_is=bias_instability_is,
                        flag=flag)
        sheet = {"value": float(value), "unit": unit, "quantity": quantity}
        if quantity == "bias instability":
            sheet["convention"] = (
                "ADEV floor: B = value / 0.6643 (sqrt(2 ln2 / pi))"
                if bias_instability_is == "adev-floor" else "B (flicker coefficient)")
        terms[QUANTITIES[quantity]] = TermPrior(canon, loose, sheet)
    if not terms:
        raise PriorError("no datasheet value given", column="--arw",
                         fix="give at least one of --arw, --bias-instability, --rrw")
    return DatasheetPrior(terms, sensor, source)


def is_prior_document(doc) -> bool:
    """Whether ``doc`` claims to be a prior document (its schema starts fogbayes.prior/)."""
    return isinstance(doc, dict) and isinstance(doc.get("schema"), str) and \
        doc["schema"].startswith(SCHEMA_NAME + "/")


def validate_prior(doc, source: str = "given") -> DatasheetPrior:
    """The :class:`DatasheetPrior` in a parsed document; a :class:`PriorError` naming
    ``source`` and the key for: another or a newer schema, no terms, a term that is not one
    of Q, N, B, K, R, a unit other than the term's canonical one, a value that is not finite
    and positive, a looseness <= 1."""
    if not isinstance(doc, dict):
        raise PriorError("a prior document is a JSON object", file=source, fix=HOW)
    from ..data.doc_kinds import refuse_other_kind

    refuse_other_kind(doc, source, ("datasheet prior document", {"prior"}, HOW), error=PriorError)
    schema = doc.get("schema")
    if not is_prior_document(doc):
        raise PriorError(f"schema {schema!r} is not {SCHEMA!r}", file=source, field="schema",
                         fix=HOW)
    version = schema.split("/", 1)[1]
    if not version.isdigit() or int(version) > SCHEMA_VERSION:
        raise PriorError(f"schema {schema!r} is newer than this fogbayes reads ({SCHEMA})",
                         file=source, field="schema",
                         fix="update fogbayes, or write the prior again with this version's "
                             "'fogbayes prior'")
    sensor = doc.get("sensor")
    if sensor is not None and not isinstance(sensor, str):
        raise PriorError("sensor is not a string", file=source, field="sensor",
                         fix="give the sensor's name as a string, or null")
    raw = doc.get("terms")
    if not isinstance(raw, dict) or not raw:
        raise PriorError("no terms (an object of N, B, K ... entries)", file=source,
                         field="terms", fix=HOW)
    terms = {}
    for t, entry in raw.items():
        key = f"terms.{t}"
        if t not in TERMS:
            raise PriorError(f"{t!r} is not a noise term", file=source, field=key,
                             fix="use the canonical names Q, N (ARW), B (bias instability), "
                                 "K (RRW), R")
        if not isinstance(entry, dict):
            raise PriorError("is not an object with value, unit and looseness", file=source,
                             field=key, fix=HOW)
        if entry.get("unit") != UNITS[t]:
            raise PriorError(f"unit {entry.get('unit')!r} is not {t}'s canonical unit "
                             f"{UNITS[t]!r}", file=source, field=f"{key}.unit",
                             fix=f"give the value in {UNITS[t]}, or {HOW}")
        value = _positive(entry.get("value"), f"{key}.value", source)
        loose = _looseness(entry.get("looseness"), f"{key}.looseness", source)
        sheet = entry.get("datasheet")
        terms[t] = TermPrior(value, loose, sheet if isinstance(sheet, dict) else None)
    return DatasheetPrior(terms, sensor, source)


def read_prior(path: str | Path) -> DatasheetPrior:
    """The validated prior document at ``path``."""
    from ..data.json_file import read_json_file

    return validate_prior(read_json_file(path, "the prior document", HOW, error=PriorError),
                          str(path))


def as_prior(prior) -> DatasheetPrior | None:
    """None, a :class:`DatasheetPrior`, a parsed document (dict) or a path, as a prior."""
    if prior is None or isinstance(prior, DatasheetPrior):
        return prior
    if isinstance(prior, dict):
        return validate_prior(prior)
    return read_prior(prior)
