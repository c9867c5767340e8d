"""An added effect in words: its size in physical units and the parameter the loop searched.

One phrase per ``steps[].detail`` (:func:`fogbayes.effects.terms.describe`), e.g.
``step: size 0.238 ± 0.018 deg/h at t = 1810 s (0.503 h) from the start``. Detail keys are
``<quantity>_<unit>`` (``_`` for ``/``, ``_per_``), values ``{"value", "stderr"}``.
"""

from __future__ import annotations

from typing import Any

from .html import fmt

#: a term's searched (or fixed) parameters: detail key -> the phrase that states it
SEARCHED = {"time_from_start_s": "at t = {v} s{h} from the start",
            "tau_s": "time constant τ = {v} s",
            "r0_degC_per_min": "knee r0 = {v} °C/min",
            "width_degC": "play width {v} °C",
            "period_s": "period {v} s"}

_UNIT_WORDS = {"deg_h": "deg/h", "degC": "°C", "deg_s": "°/s", "min": "min", "s": "s",
               "h": "h", "hz": "Hz", "rad": "rad"}


def unit_from_key(key: str) -> str:
    """``'deg_h_per_degC_per_min'`` -> ``'deg/h per (°C/min)'`` (units spelled in JSON keys)."""
    def one(u):
        return _UNIT_WORDS.get(u, u.replace("_", "/"))
    num, *den = key.split("_per_")
    if not den:
        return one(num)
    d = "/".join(one(x) for x in den)
    return f"{one(num)} per ({d})" if len(den) > 1 else f"{one(num)} per {d}"


def _split(key: str) -> tuple[str, str]:
    """``'size_deg_h'`` -> ``('size', 'deg_h')``: the quantity and its unit key."""
    for marker in ("_deg_", "_degC"):
        i = key.find(marker)
        if i > 0:
            return key[:i], key[i + 1:]
    return key, ""


def quantities(detail: dict[str, Any]) -> list[str]:
    """``'size 0.238 ± 0.018 deg/h'`` for each fitted quantity of ``detail``."""
    out = []
    for key, v in detail.items():
        if isinstance(v, dict) and "value" in v:
            name, unit = _split(key)
            se = v.get("stderr")
            pm = f" ± {fmt(se, sig=2)}" if se is not None else ""
            out.append(f"{name.replace('_minus_', ' − ').replace('_', ' ')} "
                       f"{fmt(v['value'], sig=4)}{pm} {unit_from_key(unit) if unit else ''}"
                       .rstrip())
    return out


def searched(detail: dict[str, Any]) -> list[str]:
    """The term's own parameters (step time, time constant, period, ...) in words."""
    out = []
    for key, words in SEARCHED.items():
        v = detail.get(key)
        if isinstance(v, (int, float)):
            h = f" ({fmt(v / 3600.0, sig=3)} h)" if key == "time_from_start_s" and v >= 600 else ""
            out.append(words.format(v=fmt(v, sig=4), h=h))
    return out


def effect_phrase(effect: str, detail: dict[str, Any] | None, covariates=()) -> str:
    """One added effect with its size, searched parameter and units (see module doc).

    A term with no physical reading (its coefficients only on the scaled columns) is
    named with those, said so.
    """
    detail = detail or {}
    cov = f" ({', '.join(covariates)})" if covariates and tuple(covariates) != ("time",) else ""
    bits = quantities(detail)
    where = searched(detail)
    if not bits and isinstance(detail.get("coefficients_scaled"), dict):
        bits = [f"{lab} {fmt(v['value'], sig=4)} ± {fmt(v.get('stderr'), sig=2)} deg/h"
                for lab, v in detail["coefficients_scaled"].items()]
        if bits:
            bits[-1] += " (on the centred, scaled column)"
    text = f"{effect}{cov}"
    if bits:
        text += ": " + ", ".join(bits)
    if where:
        text += (" " if bits and where[0].startswith("at ") else ", " if bits else ": ") + \
            ", ".join(where)
    return text
