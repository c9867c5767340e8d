"""IEEE Std 952 slope readouts of the noise terms from an ADEV curve (for comparison).

At the tau whose local slope is closest (within 0.25) to the term's: Q = sigma tau / sqrt3,
N = sigma sqrt(tau / 3600), B = min sigma / 0.664, K = sigma sqrt(3 3600 / tau), R = 3600 sqrt2
sigma / tau; Q, N left and K, R right of the minimum, never the longest tau; else ``None``.
Interval: the chi-square interval of sigma there through the same formula.
"""

from __future__ import annotations

import math

import numpy as np

from .model import BI_FACTOR, SLOPES, TERMS, UNITS
from .fit import TermEstimate

_TOLERANCE = 0.25


def local_slopes(tau: np.ndarray, dev: np.ndarray) -> np.ndarray:
    """d log sigma / d log tau by centred differences (one-sided at the ends)."""
    return np.gradient(np.log(dev), np.log(tau))


def _coefficient(term: str, tau: float, sigma: float) -> float:
    if term == "Q":
        return sigma * tau / math.sqrt(3.0)
    if term == "N":
        return sigma * math.sqrt(tau / 3600.0)
    if term == "B":
        return sigma / BI_FACTOR
    if term == "K":
        return sigma * math.sqrt(3.0 * 3600.0 / tau)
    return 3600.0 * math.sqrt(2.0) * sigma / tau


def slope_readouts(tau, dev, dev_low=None, dev_high=None) -> dict:
    """Readouts ``{term: TermEstimate or None}`` from an ADEV curve in deg/h (tau in s)."""
    tau, dev = np.asarray(tau, float), np.asarray(dev, float)
    lo = dev if dev_low is None else np.asarray(dev_low, float)
    hi = dev if dev_high is None else np.asarray(dev_high, float)
    slopes = local_slopes(tau, dev)
    last = len(dev) - 1  # the longest tau: a few terms, a one-sided slope; never read there
    j_min = int(np.argmin(dev[:last]))
    left, right = np.arange(j_min + 1), np.arange(j_min, last)
    out = {}
    for term in TERMS:
        if term == "B":
            j = j_min
            ok = True
        else:
            where = left if SLOPES[term] < 0 else right
            if where.size == 0:
                out[term] = None
                continue
            j = int(where[np.argmin(np.abs(slopes[where] - SLOPES[term]))])
            ok = abs(slopes[j] - SLOPES[term]) <= _TOLERANCE
        if not ok:
            out[term] = None
            continue
        out[term] = TermEstimate(_coefficient(term, tau[j], dev[j]),
                                 _coefficient(term, tau[j], lo[j]),
                                 _coefficient(term, tau[j], hi[j]), UNITS[term])
    return out
