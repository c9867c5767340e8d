"""thermal_hysteresis: rate type (h/2) tanh(dT/dt / r0), or memory (h/2) (T - P_w[T]) / (w/2)
with P_w the play operator of width w (held through a soak)."""

from __future__ import annotations

import numpy as np

from .terms import Term
from .base import Candidate, Effect, e, moving, rate_scale, thermal


class ThermalHysteresis(Effect):
    name = "thermal_hysteresis"
    what = "hysteresis"
    description = ("(h/2) tanh(dT/dt / r0): bias h higher heating than cooling (deg/h); with "
                   "width w (deg C) the memory form (h/2) (T - P_w[T]) / (w/2), P_w the play "
                   "operator")
    defaults = {"size": 0.2, "rate_scale": 0.05, "width": None}
    size_keys = ("size",)

    def plant(self, p):
        if p.get("width") is not None:
            return [(Term("play", {"channel": 0, "width": p["width"]}), [0.5 * p["size"]])]
        return [(Term("hysteresis", {"r0": p["rate_scale"]}), [0.5 * p["size"]])]

    def oracle(self, ctx, p):
        return [Term("hysteresis", {"r0": p.get("rate_scale", 0.05)})]

    def candidates(self, ctx, terms):
        if not thermal(ctx) or not moving(ctx) or \
                {tm.kind for tm in terms} & {"hysteresis", "play"}:
            return []
        # r0 below half the largest rate; widths from 0.5 deg C to a quarter of the range
        rs, span = rate_scale(ctx), np.ptp(ctx.cov.T[:, 0])
        r0s = [r for r in (0.01, 0.02, 0.05, 0.1, 0.2, 0.5) if r < 0.5 * rs]
        widths = [w for w in (0.5, 1.0, 2.0, 5.0, 10.0, 20.0) if w <= 0.25 * span]
        grid = [Term("hysteresis", e("thermal_hysteresis", r0=r)) for r in r0s] + [
            Term("play", e("thermal_hysteresis", channel=0, width=w)) for w in widths]
        if not grid:
            return []
        return [Candidate("thermal_hysteresis", "linear", tuple(grid), ("dT/dt",),
                          "r0" if not widths else "r0 or width")]
