"""Simulator entries the loop does not search as terms: Gauss-Markov noise (a noise-model
component, :mod:`fogbayes.loop.noise_model`) and paper 004's composite bias law
b = c0 + c1 x + c2 x^2 + d1 r + d2 r^2 + e x r, x = T - T_ref, r = dT/dt."""

from __future__ import annotations

from .terms import Term
from .base import Effect


class MarkovNoise(Effect):
    name = "markov_noise"
    description = "first-order Gauss-Markov noise, std sigma deg/h, correlation time tau_c s"
    defaults = {"sigma": 0.05, "tau_c": 300.0}
    size_keys = ("sigma",)
    stochastic = True

    def oracle(self, ctx, p):
        return []


class Paper004(Effect):
    name = "paper004"
    description = "paper 004 bias: order-2 polynomial in T and dT/dt (+ cross term) (deg/h)"
    defaults = {"c": [0.0, 0.0, 0.0], "d": [0.0, 0.0], "cross": 0.0, "T_ref": 0.0}

    def plant(self, p):
        x = {"channel": 0, "centre": p["T_ref"], "scale": 1.0}
        return [(Term("tpoly", {**x, "powers": list(range(len(p["c"])))}), list(p["c"])),
                (Term("rate_poly", {"powers": list(range(1, len(p["d"]) + 1)), "scale": 1.0}),
                 list(p["d"])),
                (Term("t_rate", {**x, "rate_scale": 1.0}), [p["cross"]])]
