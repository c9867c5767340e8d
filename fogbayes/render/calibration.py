"""Report sections for a loop calibration applied to a recording (``report --fit loop.json``).

What was applied (:mod:`fogbayes.loop.calibration`: each term in physical units +- 1 s.e.),
what was left out, where the recording leaves the calibrated range, and bias stability
before/after with its bootstrap interval.
"""

from __future__ import annotations

import numpy as np

from ..errors import FogbayesError
from .html import Section


def apply_loop_document(rec, doc: dict):
    """(Applied calibration, residual rate in deg/h or None) of ``doc`` on ``rec``."""
    from ..loop.calibration import apply_calibration

    applied = apply_calibration(doc, rec)
    cols = applied.columns
    if "rate" in cols:  # composite: the estimated input rate's error, deg/h
        residual = None if rec.input_rate is None else \
            (np.asarray(cols["rate"]) - rec.input_rate) * 3600.0
    else:
        residual = rec.rate("deg/h") - applied.bias_deg_h
    return applied, residual


def physical_rows(cal: dict) -> list[tuple[str, str, str, str]]:
    """Per term of a loop calibration: (effect, kind, reading in physical units, fitted
    value on the centred, scaled column(s)).

    The base polynomial (intercept + ``tpoly`` of one channel) is expanded to its raw form,
    bias = sum_j a_j T^j with T in °C (origin 0 °C): with z = (T - c) / s,
    c_k z^k = c_k s^-k sum_j binom(k, j) (-c)^(k-j) T^j, so a = A beta and the standard
    errors are sqrt(diag(A Cov A^T)) from the document's covariance. Every other term is
    read by its kind (:func:`fogbayes.effects.terms.describe`), the phrase of the loop
    report (:func:`fogbayes.render.effects.effect_phrase`).
    """
    from math import comb

    from ..effects.terms import Term, describe
    from .effects import effect_phrase
    from .html import fmt
    from .labels import coefficient_unit

    beta = np.asarray(cal["coefficients"], float)
    se = np.asarray(cal.get("stderr") or [np.nan] * beta.size, float)
    cov = cal.get("covariance")
    cov = np.asarray(cov, float) if cov is not None else np.diag(se ** 2)
    spans, i = [], 0
    for t in cal["terms"]:
        k = len(t.get("labels") or [t["kind"]])
        spans.append((t, slice(i, i + k)))
        i += k

    def scaled(t, sl):
        labs = t.get("labels") or [t["kind"]]
        return ", ".join(f"{lab} {fmt(b, sig=4)} ± {fmt(e, sig=2)}"
                         for lab, b, e in zip(labs, beta[sl], se[sl]))

    rows = []
    base = [(t, sl) for t, sl in spans if t["kind"] in ("intercept", "tpoly")]
    channels = {t["params"].get("channel") for t, _ in base if t["kind"] == "tpoly"}
    if base and len(channels) <= 1 and sum(t["kind"] == "intercept" for t, _ in base) <= 1 \
            and sum(t["kind"] == "tpoly" for t, _ in base) <= 1:
        order = max([max(t["params"]["powers"]) for t, _ in base if t["kind"] == "tpoly"] or [0])
        A = np.zeros((order + 1, beta.size))
        for t, sl in base:
            if t["kind"] == "intercept":
                A[0, sl.start] = 1.0
                continue
            c, sc = float(t["params"]["centre"]), float(t["params"]["scale"])
            for col, k in zip(range(sl.start, sl.stop), t["params"]["powers"]):
                for j in range(k + 1):
                    A[j, col] += comb(k, j) * (-c) ** (k - j) / sc ** k
        a = A @ beta
        a_se = np.sqrt(np.clip(np.einsum("ij,jk,ik->i", A, cov, A), 0.0, None))
        units = {"output": "deg/h", "T": "degC"}
        reading = "; ".join(
            f"{'constant' if j == 0 else f'T^{j}'} {fmt(a[j], sig=4)} ± {fmt(a_se[j], sig=2)} "
            f"{coefficient_unit([j], ['T'], units)}" for j in range(order + 1))
        rows.append(("base", " + ".join(t["kind"] for t, _ in base),
                     f"bias polynomial in T [°C], origin 0 °C: {reading}",
                     "; ".join(scaled(t, sl) for t, sl in base)))
        spans = [(t, sl) for t, sl in spans if (t, sl) not in base]
    for t, sl in spans:
        detail = describe(Term(t["kind"], t.get("params") or {}), beta[sl], se[sl])
        detail.pop("term", None)
        rows.append((t["effect"], t["kind"], effect_phrase(t["effect"], detail).split(": ", 1)[-1]
                     if t["effect"] != "base" else effect_phrase(t["kind"], detail),
                     scaled(t, sl)))
    return rows


def calibration_section(doc: dict, applied) -> Section:
    """The terms applied, in physical units (raw form), and what the report user should know."""
    cal = doc["calibration"]
    sec = Section("Calibration applied (from the closed loop)")
    run = doc["input"].get("file") or "its run"
    sec.text(f"Model '{doc['model']}' as the loop left it on {run} ({doc['schema']}). Each "
             "term in physical units, ± 1 s.e. (the loop report's numbers); the value fitted "
             "on the term's centred, scaled column, in deg/h, is beside it.")
    skipped = {s["kind"] for s in applied.skipped}
    applies = {t["kind"]: t["applies"] for t in cal["terms"]}
    rows = [[effect, kind, reading, scaled_text,
             "left out (run event)" if kind in skipped else applies.get(kind.split(" + ")[0], "")]
            for effect, kind, reading, scaled_text in physical_rows(cal)]
    sec.table(["effect", "term", "in physical units (± 1 s.e.)",
               "fitted on the centred, scaled column [deg/h]", "applied as"], rows)
    for o in applied.outside:
        lo, hi = o["calibrated"]
        sec.note(f"{o['covariate']}: {100 * o['share']:.1f} % of the samples lie outside the "
                 f"calibrated range [{lo:.3g}, {hi:.3g}] (extrapolated).", ok=False)
    return sec


def calibration_headline(rec, doc: dict, residual, seed: int) -> Section:
    """Headline: the bias stability before/after the calibration, with its interval."""
    from .bootstrap import stability_intervals
    from .headline import headline_section, improvement_verdict

    added = [t["effect"] for t in doc["calibration"]["terms"] if t["effect"] != "base"]
    model = f"loop calibration '{doc['model']}' with {', '.join(added) or 'the base terms only'}"
    if residual is None:
        return headline_section(rec, model=model, verdict="Composite calibration: no input "
                                "rate in this recording to compare with.", ok=None)
    try:
        si = stability_intervals(rec.rate("deg/h"), {"after": residual}, rec.time,
                                 window_s=1.0, seed=seed)["after"]
    except (ValueError, FogbayesError):
        return headline_section(rec, model=model, verdict="The record is too short for a "
                                "bias stability with an interval.", ok=False)
    verdict, ok = improvement_verdict(si, "The loop's calibration")
    return headline_section(rec, model=model, rows=[("raw → calibrated", "", si)],
                            verdict=verdict, ok=ok)
