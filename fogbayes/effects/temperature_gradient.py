"""temperature_gradient: b = k (T_b - T_a) between two temperature channels."""

from __future__ import annotations

import numpy as np

from .terms import Term
from .base import Candidate, Effect, e, thermal


class TemperatureGradient(Effect):
    name = "temperature_gradient"
    what = "a gradient term"
    description = "k (T2 - T1) between the two channels (deg/h per deg C)"
    defaults = {"coeff": 0.03}
    size_keys = ("coeff",)
    requires = ("temperature_2",)
    separable_by_programme = True

    def plant(self, p):
        return [(Term("gradient", {"a": 0, "b": 1, "scale": 1.0}), [p["coeff"]])]

    def oracle(self, ctx, p):
        return [Term("gradient", {"a": 0, "b": 1, "scale": 1.0})]

    def candidates(self, ctx, terms):
        cov = ctx.cov
        if not thermal(ctx) or cov.n_temps < 2 or "gradient" in {tm.kind for tm in terms}:
            return []
        grid = []
        for j in range(1, cov.n_temps):
            d = cov.T[:, j] - cov.T[:, 0]
            if np.ptp(d) > 0.05:
                grid.append(Term("gradient", e("temperature_gradient", a=0, b=j,
                                               scale=max(float(np.max(np.abs(d))), 1e-3))))
        if not grid:
            return []
        return [Candidate("temperature_gradient", "linear", tuple(grid),
                          tuple(["temperature"] + [cov.names[t.params["b"]] for t in grid]),
                          "channel" if len(grid) > 1 else None)]
