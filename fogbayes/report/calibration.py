"""Report sections for a loop calibration applied to a recording (``report --fit loop.json``).

The loop document's calibration (:mod:`fogbayes.loop.calibration`) is applied to the
recording being reported -- usually another run of the sensor -- and the report says what
was applied (each term, sensor property or run event, its coefficient +- 1 s.e. on the
centred/scaled column), what was left out, where the recording leaves the calibrated
range, and the bias stability before/after with its bootstrap interval.
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


def calibration_section(doc: dict, applied) -> Section:
    """The terms applied, with their coefficients, and what the report user should know."""
    cal = doc["calibration"]
    sec = Section("Calibration applied (from the closed loop)")
    run = doc["input"].get("file") or "its run"
    sec.text(f"Model '{doc['model']}' as the loop left it on {run} ({doc['schema']}); "
             "coefficients in deg/h on centred, scaled columns, +- 1 s.e.")
    se = cal.get("stderr") or [float("nan")] * len(cal["coefficients"])
    rows, i = [], 0
    skipped = {s["kind"] for s in applied.skipped}
    for t in cal["terms"]:
        k = len(t.get("labels") or [t["kind"]])
        for lab, c, s in zip(t.get("labels") or [t["kind"]], cal["coefficients"][i:i + k],
                             se[i:i + k]):
            rows.append([t["effect"], t["kind"], lab, f"{c:.6g}", f"{s:.3g}",
                         "left out (run event)" if t["kind"] in skipped else t["applies"]])
        i += k
    sec.table(["effect", "term", "column", "coefficient (deg/h)", "s.e.", "applied as"], rows)
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
