"""temperature_rate (Shupe): b = k dT/dt, k in deg/h per deg C/min."""

from __future__ import annotations

from .terms import Term
from .base import Candidate, Effect, e, moving, rate_scale, thermal


class TemperatureRate(Effect):
    name = "temperature_rate"
    what = "a Shupe (dT/dt) term"
    description = "Shupe term k dT/dt (deg/h per deg C/min)"
    defaults = {"coeff": 0.3}
    size_keys = ("coeff",)
    separable_by_programme = True
    processing = {"temperature_rate": "Savitzky-Golay (order 2) slope of block-mean "
                                      "temperature over rate_window_s, chamber corners kept; "
                                      "deg C/min of the first channel"}

    def plant(self, p):
        return [(Term("rate", {"scale": 1.0}), [p["coeff"]])]

    def oracle(self, ctx, p):
        return [Term("rate", {"scale": 1.0})]

    def candidates(self, ctx, terms):
        if not thermal(ctx) or not moving(ctx) or {tm.kind for tm in terms} & {"rate", "rate_poly"}:
            return []
        return [Candidate("temperature_rate", "linear", (Term("rate", e(
            "temperature_rate", scale=rate_scale(ctx))),), ("dT/dt",), None)]
