"""The loop's final model as a calibration: written into the loop document, applied to new runs.

Section ``calibration`` of ``fogbayes.loop/1`` (family, terms, coefficients in deg/h on the
scaled columns, stderr, covariance, processing, valid ranges, noise), read by ``fogbayes
compensate --params``. bias(t) = sum_j X_j(cov(t)) c_j, the columns of
:mod:`fogbayes.effects.terms` on the new recording's covariates. Bias family: output - bias;
composite: W solving U = f(W, T, t) (:func:`fogbayes.loop.compensate.solve_rate`). Terms with
``applies: "run"`` are carried only with ``run_events=True``; warm-up time counts from the first sample.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np

from .context import spike_flags
from ..preprocess.covariates import block_grid, covariates_of
from ..effects import REGISTRY
from ..effects.terms import KINDS, Term, design, labels
from ..data.units import convert_rate
from .compensate import solve_rate
from .noise_model import components


#: Term kinds tied to the calibration run's clock (not carried to a new run by default).
RUN_EVENT_KINDS = tuple(k for k, v in KINDS.items() if v.applies == "run")
#: Term kinds that act on the input rate (the composite family inverts them).
OMEGA_KINDS = ("omega_poly", "omega_abs", "omega_tpoly")
#: The block grid and dT/dt window of the loop's covariates (context.make_context).
TARGET_BLOCKS = 2500
RATE_WINDOW_S = 60.0


def processing() -> dict[str, Any]:
    """The calibration's ``processing`` section: the time origin, each registered effect's
    covariates (:attr:`fogbayes.effects.Effect.processing`), the block grid, outliers, fit."""
    return {
        "time_origin": "first sample of the recording (taken as power-on)",
        **{k: v for fx in REGISTRY.values() for k, v in fx.processing.items()},
        "rate_window_s": RATE_WINDOW_S,
        "target_blocks": TARGET_BLOCKS,
        "outliers": "isolated spikes of the first difference beyond 6 sigma_MAD: flagged, left "
                    "out of the fit, kept (compensated) in the output",
        "fit": "generalised least squares on block means; white + flicker + random-walk "
               "(+ Gauss-Markov) noise by maximum likelihood",
    }


def _range(x) -> list[float] | None:
    if x is None or np.size(x) == 0:
        return None
    return [float(np.min(x)), float(np.max(x))]


def calibration_json(fit, ctx, model: str) -> dict[str, Any]:
    """The ``calibration`` section of the loop's final ``fit`` on context ``ctx``."""
    terms = []
    for tm in fit.terms:
        params = {k: v for k, v in tm.params.items() if k != "effect"}
        terms.append({"kind": tm.kind, "effect": tm.params.get("effect", "base"),
                      "params": params, "labels": labels(tm), "applies": tm.applies})
    cov = ctx.cov
    keep = ~ctx.outlier
    valid = {"duration_s": float(cov.duration),
             "temperature": [_range(cov.T[keep, j]) for j in range(cov.n_temps)],
             "temperature_names": list(cov.names),
             "temperature_rate_degC_per_min": _range(None if cov.Tdot is None
                                                     else cov.Tdot[keep]),
             "input_rate_deg_s": _range(None if cov.omega is None else cov.omega[keep])}
    nf = fit.noise
    cb = np.asarray(nf.cov_beta, float)
    return {"family": "composite" if model == "composite" else "bias",
            "terms": terms,
            "coefficients": [float(b) for b in nf.beta],
            "stderr": [float(s) for s in np.sqrt(np.clip(np.diag(cb), 0.0, None))],
            "covariance": cb.tolist(),
            "processing": {**processing(), "block_s": float(ctx.grid.dt)},
            "valid": valid,
            "noise": {"white_variance_block": float(nf.sigma2), "block_s": float(nf.spec.dt),
                      "flicker_bank": bool(nf.spec.bank_taus),
                      "random_walk": bool(nf.spec.random_walk),
                      "gauss_markov_components": int(nf.spec.n_markov),
                      "gauss_markov": components(fit),
                      "converged": bool(nf.converged)}}


def input_json(rec) -> dict[str, Any]:
    """What a new recording must provide: unit, scale factor, channels, input rate."""
    return {"unit": rec.unit, "scale_factor": rec.scale_factor,
            "temperatures": list(rec.temperature_names),
            "input_rate": rec.input_rate is not None,
            "sensor_id": rec.meta.sensor_id, "file": rec.meta.source}


class Applied(NamedTuple):
    """A calibration applied to a recording: output columns and what the user should know."""

    columns: dict[str, np.ndarray]   # time, output (or rate), outlier
    bias_deg_h: np.ndarray | None    # the subtracted bias (bias family), deg/h
    skipped: list[dict]              # run-event terms not applied
    outside: list[dict]              # covariates outside the calibrated range


def applied_terms(cal: dict, run_events: bool = False):
    """(terms, coefficients, skipped) of a calibration applied to a new run: run events are
    left out (and listed) unless ``run_events``; the kind decides, not the document."""
    terms, beta, skipped, i = [], [], [], 0
    for d in cal["terms"]:
        tm = Term(d["kind"], dict(d["params"]))
        k = tm.n_cols
        if tm.applies == "run" and not run_events:
            skipped.append({"effect": d.get("effect"), "kind": tm.kind,
                            "why": "a run event of the calibration run (pass run events "
                                   "to apply it)"})
        else:
            terms.append(tm)
            beta.extend(cal["coefficients"][i:i + k])
        i += k
    return terms, np.asarray(beta, float), skipped


class RangeCheck:
    """Samples whose covariates lie outside the calibration run's range, counted over one
    record or over the chunks of one (:meth:`add` each, then :meth:`report`)."""

    def __init__(self, valid: dict, names: list[str]):
        self.checks = [(f"temperature '{names[j]}' (deg C)", ("T", j), rng)
                       for j, rng in enumerate(valid.get("temperature") or [])
                       if j < len(names) and rng is not None]
        for what, key, rng in (("dT/dt (deg C/min)", ("Tdot", None),
                                valid.get("temperature_rate_degC_per_min")),
                               ("input rate (deg/s)", ("omega", None),
                                valid.get("input_rate_deg_s"))):
            if rng is not None:
                self.checks.append((what, key, rng))
        self.n = 0
        self.seen = {what: [0, np.inf, -np.inf] for what, _, _ in self.checks}

    def add(self, cov) -> None:
        for what, (field, j), (lo, hi) in self.checks:
            x = getattr(cov, field)
            if x is None:
                continue
            x = x[:, j] if j is not None else x
            tol = 1e-6 * max(abs(lo), abs(hi), 1.0)  # the run's own ends are inside
            s = self.seen[what]
            s[0] += int(np.count_nonzero((x < lo - tol) | (x > hi + tol)))
            s[1], s[2] = min(s[1], float(np.min(x))), max(s[2], float(np.max(x)))
        self.n += int(cov.t.size)

    def report(self) -> list[dict]:
        out = []
        for what, _, (lo, hi) in self.checks:
            n, xmin, xmax = self.seen[what]
            if n:
                out.append({"covariate": what, "samples": n, "share": n / self.n,
                            "calibrated": [lo, hi], "seen": [xmin, xmax],
                            "beyond_by": float(max(lo - xmin, xmax - hi, 0.0)),
                            "calibrated_span": hi - lo})
        return out


def apply_calibration(doc: dict, rec, *, run_events: bool = False) -> Applied:
    """Compensate recording ``rec`` with the (validated) loop document ``doc``.

    ``rec`` must carry the document's temperature channels (matched by name, in the
    document's order; :func:`fogbayes.loop.calibration_doc.match_channels`).
    """
    from .calibration_doc import match_channels

    cal = doc["calibration"]
    rec = match_channels(doc, rec)
    rate = rec.rate("deg/h")
    outlier = spike_flags(rate)
    proc = cal.get("processing") or {}
    grid = block_grid(rec.time, rec.sample_rate, use=~outlier,
                      target_blocks=int(proc.get("target_blocks", TARGET_BLOCKS)))
    cov = covariates_of(rec, grid, rate_window_s=float(proc.get("rate_window_s",
                                                                  RATE_WINDOW_S)))
    terms, beta, skipped = applied_terms(cal, run_events)
    cols = {"time": np.asarray(rec.time, float)}
    bias = None
    if cal["family"] == "composite":
        cols["rate"] = solve_rate(terms, beta, cov, rate)
    else:
        bias = design(terms, cov) @ beta if terms else np.zeros(rec.n)
        cols["output"] = convert_rate(rate - bias, "deg/h", rec.unit,
                                      scale_factor=rec.scale_factor)
    cols["outlier"] = outlier | ~np.isfinite(cols["rate"]) if "rate" in cols else outlier
    ranges = RangeCheck(cal.get("valid") or {}, list(cov.names))
    ranges.add(cov)
    return Applied(cols, bias, skipped, ranges.report())
