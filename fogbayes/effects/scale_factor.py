"""Scale-factor effects on a rate table (w the input rate in deg/s, nominal scale 3600):
nonlinearity 3600 (k2 w^2 + k3 w^3), asymmetry 1800 a |w|, temperature 3600 w k (T - T_ref)."""

from __future__ import annotations

import numpy as np

from .terms import Term
from .base import Candidate, Effect, count, e, rate_table, tscale, wscale


class _OnRateTable(Effect):
    requires = ("input_rate",)


def _ws(ctx) -> float:
    """The input rate's scale (1 without an input rate)."""
    return wscale(ctx) if ctx.cov.omega is not None else 1.0


class ScaleFactorNonlinearity(_OnRateTable):
    name = "scale_factor_nonlinearity"
    description = "3600 (k2 w^2 + k3 w^3) deg/h, w in deg/s"
    defaults = {"k2": 1e-6, "k3": 1e-8}
    size_keys = ("k2", "k3")
    max_times = 2

    def plant(self, p):
        return [(Term("omega_poly", {"powers": [2, 3], "scale": 1.0}),
                 [3600.0 * p["k2"], 3600.0 * p["k3"]])]

    def oracle(self, ctx, p):
        return [Term("omega_poly", {"powers": [2, 3], "scale": _ws(ctx)})]

    def candidates(self, ctx, terms):
        if not rate_table(ctx):
            return []
        wpow = [x for tm in terms if tm.kind == "omega_poly" for x in tm.params["powers"]]
        ws = wscale(ctx)
        top = max(wpow) if wpow else 1
        if count(terms, self.name) >= self.max_times or top >= 6:
            return []
        return [Candidate("scale_factor_nonlinearity", "linear", (
            Term("omega_poly", e("scale_factor_nonlinearity", powers=[top + 1], scale=ws)),
            Term("omega_poly", e("scale_factor_nonlinearity", powers=[top + 1, top + 2],
                                 scale=ws))), ("input_rate",), "order")]


class ScaleFactorAsymmetry(_OnRateTable):
    name = "scale_factor_asymmetry"
    description = "1800 a |w| deg/h: scale (1 +- a/2) for w > 0 / w < 0"
    defaults = {"asymmetry": 1e-4}
    size_keys = ("asymmetry",)

    def plant(self, p):
        return [(Term("omega_abs", {"scale": 1.0}), [1800.0 * p["asymmetry"]])]

    def oracle(self, ctx, p):
        return [Term("omega_abs", {"scale": _ws(ctx)})]

    def candidates(self, ctx, terms):
        if not rate_table(ctx) or "omega_abs" in {tm.kind for tm in terms}:
            return []
        return [Candidate("scale_factor_asymmetry", "linear", (Term("omega_abs", e(
            "scale_factor_asymmetry", scale=wscale(ctx))),), ("input_rate",), None)]


class ScaleFactorTemperature(_OnRateTable):
    name = "scale_factor_temperature"
    description = "3600 w k (T - T_ref) deg/h: scale linear in T"
    defaults = {"coeff": 1e-6, "T_ref": 20.0}
    size_keys = ("coeff",)

    def plant(self, p):
        return [(Term("omega_tpoly", {"channel": 0, "powers": [1], "centre": p["T_ref"],
                                      "t_scale": 1.0, "scale": 1.0}), [3600.0 * p["coeff"]])]

    def oracle(self, ctx, p):
        c, s = tscale(ctx)
        return [Term("omega_tpoly", {"channel": 0, "powers": [1], "centre": c, "t_scale": s,
                                     "scale": _ws(ctx)})]

    def candidates(self, ctx, terms):
        cov = ctx.cov
        if not rate_table(ctx) or not cov.n_temps or np.ptp(cov.T[:, 0]) < 0.5:
            return []
        centre, scale = tscale(ctx)
        tpow = [x for tm in terms if tm.kind == "omega_tpoly" and tm.params.get("wpower", 1) == 1
                for x in tm.params["powers"]]
        k = (max(tpow) if tpow else 0) + 1
        if k > 4:
            return []
        return [Candidate("scale_factor_temperature", "linear", (Term("omega_tpoly", e(
            "scale_factor_temperature", channel=0, powers=[k], centre=centre,
            t_scale=scale, scale=wscale(ctx))),), ("input_rate", "temperature"), None)]
