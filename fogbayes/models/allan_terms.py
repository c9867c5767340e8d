"""The five Allan-variance noise terms: their names, the canonical units fogbayes documents
state them in, and the bias-instability factor (IEEE 952 C.1).

Shared vocabulary below :mod:`fogbayes.inference` and the model families: the Allan family's
model (:mod:`fogbayes.allan.model`, which offers these names and holds the formulas) and the
datasheet prior (:mod:`fogbayes.inference.datasheet`) both use it, and imports point one way,
so the inference layer never imports a family.
"""

from __future__ import annotations

import math

TERMS = ("Q", "N", "B", "K", "R")
UNITS = {"Q": "arcsec", "N": "deg/sqrt(h)", "B": "deg/h", "K": "deg/h^1.5", "R": "deg/h^2"}
BI_FACTOR = math.sqrt(2.0 * math.log(2.0) / math.pi)  # 0.6643: ADEV floor = BI_FACTOR * B
