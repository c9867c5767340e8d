"""Typed results of the closed loop and their JSON form (docs/DESIGN.md contract).

``LoopResult.to_json()``: ``schema`` ``fogbayes.loop/1``, ``model``, ``initial``/``final``
(rms, bias_stability in deg/h, elpd in nats), ``steps``, ``unexplained``, ``noise_model``
(:mod:`fogbayes.loop.noise_model`), ``input``, ``calibration`` (:mod:`fogbayes.loop.calibration`),
and ``noise_prior`` under one (:mod:`fogbayes.loop.noise_prior`).
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np

from ..support.jsonable import to_jsonable
from .context import Context
from .fitting import ModelFit
from .noise_prior import NoisePrior
from ..effects.terms import Term
from .metrics import Metrics
from .noise_model import components


class Step(NamedTuple):
    """One addition: the effect, its term, the evidence for it and the metrics after it."""

    effect: str
    covariates: tuple[str, ...]
    term: Term
    detail: dict[str, Any]
    evidence: dict[str, Any]
    rms_before: float
    rms_after: float
    metrics_after: Metrics
    fit: ModelFit


class Rejected(NamedTuple):
    """Why the loop stopped: the best remaining candidate and its evidence."""

    reason: str
    evidence: dict[str, Any]


class LoopResult(NamedTuple):
    """Everything the loop did (see module doc); ``fit`` is the final model."""

    model: str
    initial: Metrics
    steps: list[Step]
    final: Metrics
    unexplained: list[dict[str, Any]]
    fit: ModelFit
    initial_fit: ModelFit
    stop: Rejected
    context: Context
    compensated: dict[str, np.ndarray]
    rule: str
    noise_prior: NoisePrior | None = None
    input: dict | None = None          # unit, scale factor, channels of the recording
    calibration: dict | None = None    # the final model, applicable to new runs
    warnings: tuple = ()               # drivers the record cannot tell apart (identifiable)
    noise_selection: tuple = ()        # Gauss-Markov add/drop decisions (noise_model.choose)
    noise_adev: dict | None = None     # allan: ADEV misfit without/with the components
    holdout: dict | None = None        # time-blocked CV: base and final lpd, terms not kept
    detectable: tuple = ()             # per candidate: the size that could go unseen

    @property
    def effects(self) -> list[str]:
        return [s.effect for s in self.steps]

    def to_json(self) -> dict[str, Any]:
        def m(x: Metrics) -> dict:
            return {"rms": x.rms, "bias_stability": x.bias_stability, "elpd": x.elpd}

        steps = [{"effect": s.effect, "covariates": list(s.covariates), "detail": s.detail,
                  "evidence": s.evidence, "rms_before": s.rms_before, "rms_after": s.rms_after}
                 for s in self.steps]
        from ..data.doc_rules import LOOP_SCHEMA

        doc = {"schema": LOOP_SCHEMA, "model": self.model, "initial": m(self.initial),
               "steps": steps, "final": m(self.final), "unexplained": self.unexplained,
               "noise_model": {"components": components(self.fit),
                               "selection": list(self.noise_selection)}}
        if self.noise_adev is not None:
            doc["noise_model"]["adev_misfit"] = self.noise_adev
        if self.holdout is not None:
            doc["holdout"] = self.holdout
        if self.noise_prior is not None:  # an assumption every number above depends on
            doc["noise_prior"] = self.noise_prior.to_json(self.context.grid.dt)
        if self.detectable:
            doc["detectable"] = list(self.detectable)
        if self.warnings:
            doc["warnings"] = list(self.warnings)
        if self.calibration is not None:
            doc["input"] = self.input
            doc["calibration"] = self.calibration
        return to_jsonable(doc)
