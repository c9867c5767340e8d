"""The five Allan-variance noise terms: names, canonical units, and the bias-instability factor (IEEE 952 C.1).

Shared by :mod:`fogbayes.allan.model` and :mod:`fogbayes.inference.datasheet`, below both.
"""

from __future__ import annotations

import math

TERMS = ("Q", "N", "B", "K", "R")
UNITS = {"Q": "arcsec", "N": "deg/sqrt(h)", "B": "deg/h", "K": "deg/h^1.5", "R": "deg/h^2"}
BI_FACTOR = math.sqrt(2.0 * math.log(2.0) / math.pi)  # 0.6643: ADEV floor = BI_FACTOR * B
