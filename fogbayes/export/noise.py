"""Noise coefficients for filters: IEEE 952 terms in SI units, Kalibr/OpenVINS ``imu.yaml``.

Factors document -> SI (docs/units.md): Q arcsec -> rad pi/648000; N deg/sqrt(h) -> rad/sqrt(s)
(pi/180)/60; B deg/h -> rad/s (pi/180)/3600; K deg/h^1.5 -> rad/s^2/sqrt(Hz) (pi/180)/216000;
R deg/h^2 -> rad/s^2 (pi/180)/3600^2. ADEV floor = 0.664 B; discrete N_d = N sqrt(fs), K_d = K / sqrt(fs).
``imu.yaml``: ``gyroscope_noise_density`` = N, ``gyroscope_random_walk`` = K (largest axis);
``quantile`` 0.5 or the document interval's ends, others refused.
"""

from __future__ import annotations

import math

from ..errors import FogbayesError
from ..allan.model import BI_FACTOR, UNITS as DOC_UNITS  # the document's units, ADEV floor / B

DEG = math.pi / 180.0
#: document unit -> SI factor per term (see the table above)
TO_SI = {"Q": (DEG / 3600.0, "rad"), "N": (DEG / 60.0, "rad/s/sqrt(Hz)"),
         "B": (DEG / 3600.0, "rad/s"), "K": (DEG / 3600.0 / 60.0, "rad/s^2/sqrt(Hz)"),
         "R": (DEG / 3600.0 ** 2, "rad/s^2")}


class NoiseExportError(FogbayesError):
    """The document cannot give the requested noise export."""


def _terms(doc: dict, source: str | None) -> dict:
    if not isinstance(doc, dict) or doc.get("model") != "allan":
        raise NoiseExportError("not an Allan document (its 'model' is "
                               f"{doc.get('model') if isinstance(doc, dict) else None!r})",
                               file=source, field="model",
                               fix="pass the document of 'fogbayes allan --json'")
    terms = (doc.get("fit") or {}).get("terms") or {}
    for t, unit in DOC_UNITS.items():
        e = terms.get(t)
        if e is not None and e.get("unit") != unit:
            raise NoiseExportError(f"term {t} is in {e.get('unit')!r}, expected {unit!r}",
                                   file=source, field=f"fit.terms.{t}.unit",
                                   fix="write the document again with this fogbayes")
    return terms


def quantile_key(quantile: float, ci: float, source: str | None = None) -> str:
    """Which of value/low/high holds ``quantile`` of a document whose intervals are ``ci``."""
    lo, hi = (1.0 - ci) / 2.0, (1.0 + ci) / 2.0
    for q, key in ((0.5, "value"), (lo, "low"), (hi, "high")):
        if abs(quantile - q) < 1e-9:
            return key
    raise NoiseExportError(
        f"quantile {quantile:g} is not in the document (it holds the estimate, 0.5, and the "
        f"{ci:g} interval's ends {lo:g} and {hi:g})", file=source, column="--quantile",
        fix=f"use --quantile 0.5, {lo:g} or {hi:g}")


def ieee952_document(doc: dict, *, source: str | None = None) -> dict:
    """The five terms with intervals in the document's units and in SI (continuous and,
    for N and K, discrete time at the record's rate)."""
    terms, fs, ci = _terms(doc, source), float(doc["fs"]), float(doc.get("ci", 0.9))
    out = {}
    for t, (f, si_unit) in TO_SI.items():
        e = terms.get(t)
        if e is None:
            continue
        row = {"unit": e["unit"], "value": e["value"], "low": e["low"], "high": e["high"],
               "present": bool(e.get("present", True)), "si_unit": si_unit,
               "si": {k: e[k] * f for k in ("value", "low", "high")}}
        if t == "N":
            row["discrete"] = {"unit": "rad/s", "at_hz": fs,
                               **{k: e[k] * f * math.sqrt(fs) for k in ("value", "low", "high")}}
        if t == "K":
            row["discrete"] = {"unit": "rad/s", "at_hz": fs,
                               **{k: e[k] * f / math.sqrt(fs) for k in ("value", "low", "high")}}
        if t == "B":
            row["adev_floor"] = {k: e[k] * BI_FACTOR for k in ("value", "low", "high")}
        out[t] = row
    return {"schema": "fogbayes.ieee952/1", "sensor_id": doc.get("sensor_id"),
            "source": doc.get("source"), "fs": fs, "ci": ci,
            "interval": "value = the fit's estimate; [low, high] its two-sided ci interval",
            "terms": out}


def kalibr_yaml(docs: list[tuple[dict, str | None]], *, quantile: float = 0.5,
                topic: str = "/imu0") -> str:
    """Kalibr/OpenVINS ``imu.yaml`` text (gyroscope keys) from one Allan document per axis."""
    rows = []
    for doc, src in docs:
        terms = _terms(doc, src)
        key = quantile_key(quantile, float(doc.get("ci", 0.9)), src)
        for t in ("N", "K"):
            if terms.get(t) is None:
                raise NoiseExportError(f"the document has no {t} term", file=src,
                                       field=f"fit.terms.{t}", fix="fit the five-term model")
            if not terms[t][key] > 0:  # a filter told "no noise" trusts its model forever
                raise NoiseExportError(
                    f"{t} is {terms[t][key]:g} at quantile {quantile:g}: the data do not "
                    f"resolve {t} (its interval reaches 0), and a filter given 0 would never "
                    "doubt its model", file=src, field=f"fit.terms.{t}",
                    fix="use --quantile 0.5 (the estimate) or the interval's upper end")
        unresolved = [t for t in ("N", "K") if not terms[t].get("present", True)]
        rows.append((src, float(doc["fs"]), terms["N"][key] * TO_SI["N"][0],
                     terms["K"][key] * TO_SI["K"][0], unresolved))
    for src, fs, *_ in rows[1:]:
        if fs != rows[0][1]:
            raise NoiseExportError(f"the axes were recorded at different rates ({rows[0][1]:g} "
                                   f"Hz in {rows[0][0]}, {fs:g} Hz here)", file=src,
                                   field="fs", fix="export each sensor alone")
    n_max, k_max = max(r[2] for r in rows), max(r[3] for r in rows)
    what = {"value": "the estimate (quantile 0.5)", "low": f"quantile {quantile:g}",
            "high": f"quantile {quantile:g}"}[key]
    lines = ["# IMU noise model for Kalibr / OpenVINS, written by fogbayes export",
             "# continuous-time densities in SI units (docs/units.md):",
             "#   gyroscope_noise_density = N (angle random walk)  [rad/s/sqrt(Hz)]",
             "#   gyroscope_random_walk   = K (rate random walk)   [rad/s^2/sqrt(Hz)]",
             f"# each is {what} of the fogbayes Allan fit"
             + (" ; the largest of the axes:" if len(rows) > 1 else ":")]
    for src, _, n, k, unresolved in rows:
        flag = f" ({', '.join(unresolved)} not resolved by the data: its interval reaches 0)" \
            if unresolved else ""
        lines.append(f"#   {src}: N = {n:.6e}, K = {k:.6e}{flag}")
    lines.append("# the accelerometer keys are not written: fogbayes fitted the gyroscope only")
    lines += [f"rostopic: {topic}", f"update_rate: {rows[0][1]:.9g}",
              f"gyroscope_noise_density: {n_max:.9e}", f"gyroscope_random_walk: {k_max:.9e}"]
    return "\n".join(lines) + "\n"
