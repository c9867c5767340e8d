"""periodic: b = A sin(2 pi f t + phase); the loop scans f by FFT (a "spectral" candidate)."""

from __future__ import annotations

import numpy as np

from .terms import Term
from .base import Candidate, Effect, count


class Periodic(Effect):
    name = "periodic"
    applies = "run"
    description = "A sin(2 pi f t + phase) (deg/h, Hz)"
    defaults = {"amplitude": 0.1, "frequency": 1.0 / 600.0, "phase": 0.0}
    size_keys = ("amplitude",)
    max_times = 3

    def plant(self, p):
        a, ph = p["amplitude"], p["phase"]  # A sin(wt + ph) = A cos(ph) sin(wt) + A sin(ph) cos(wt)
        return [(Term("periodic", {"frequency": p["frequency"]}),
                 [a * np.cos(ph), a * np.sin(ph)])]

    def oracle(self, ctx, p):
        return [Term("periodic", {"frequency": p.get("frequency", 1 / 600)})]

    def candidates(self, ctx, terms):
        if count(terms, self.name) >= self.max_times:
            return []
        return [Candidate("periodic", "spectral", (), ("time",), "frequency")]
