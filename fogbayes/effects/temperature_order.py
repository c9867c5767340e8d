"""temperature_order: bias polynomial b = sum_i c_i (T - T_ref)^i; the loop adds one power."""

from __future__ import annotations

from .terms import Term
from .base import Candidate, Effect, count, e, thermal, tpoly, tscale


class TemperatureOrder(Effect):
    name = "temperature_order"
    what = "a higher power of T"
    description = "bias polynomial in temperature, sum_i c_i (T - T_ref)^i (deg/h)"
    # a quartic: the power above the bias-t base's cubic (loop/bases.py)
    defaults = {"coeffs": [0.0, 0.0, 0.0, 0.0, 1e-7], "T_ref": 20.0}
    same_on_top = ("T_ref",)
    max_times = 3

    def plant(self, p):
        return [(Term("tpoly", {"channel": 0, "powers": list(range(len(p["coeffs"]))),
                                "centre": p["T_ref"], "scale": 1.0}), list(p["coeffs"]))]

    def on_top(self, mine, extra):
        """Polynomials add, coefficient by coefficient (same ``T_ref``):
        sum_i (a_i + c_i) (T - T_ref)^i, a the scenario's, c the default."""
        a, c = list(mine["coeffs"]), list(extra["coeffs"])
        n = max(len(a), len(c))
        a, c = a + [0.0] * (n - len(a)), c + [0.0] * (n - len(c))
        return {**mine, "coeffs": [float(x + y) for x, y in zip(a, c)]}

    def oracle(self, ctx, p):
        c, s = tscale(ctx)
        return [Term("tpoly", {"channel": 0, "powers": [len(p["coeffs"]) - 1], "centre": c,
                                "scale": s})]

    def candidates(self, ctx, terms):
        if not thermal(ctx):
            return []
        centre, scale = tscale(ctx)
        tp = tpoly(terms)
        order = max(tp.params["powers"]) if tp is not None else 0
        if count(terms, self.name) < self.max_times and order < 6:
            return [Candidate("temperature_order", "linear", (Term("tpoly", e(
                "temperature_order", channel=0, powers=[order + 1], centre=centre,
                scale=scale)),), ("temperature",), None)]
        return []
