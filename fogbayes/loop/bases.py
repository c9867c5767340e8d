"""Base models the loop starts from, as term lists, and which effects each may gain.

bias-t: c0 + sum_{k<=n} c_k T'^k (n = 3, ``fogbayes fit``'s default); thermal: bias-t +
sum_{j<=m} d_j (dT/dt)'^j (paper 004 eq. 14); composite: U = S1(T) S2(W) W + U0(T)
[+ U1(T) t] linearised (paper 000; orders "s1,s2,u0[,u1]",
:func:`fogbayes.composite.model.read_orders`, default "0,0,2,-"); allan: a constant, only
noise terms may be added. T' = (T - centre) / scale, W' = W / max|W|; temperature terms are
left out when T spans < 0.1 deg C. Orders grammar and defaults of
:mod:`fogbayes.thermal.workflow` (a higher T order is a loop step, ``temperature_order``).
"""

from __future__ import annotations

import numpy as np

from .context import Context
from ..effects.terms import Term
from ..errors import FogbayesError, MissingColumnError
from ..composite.model import OrdersError, read_orders
from ..thermal.workflow import DEFAULT_ORDERS
from ..effects import REGISTRY
from ..effects.periodic import Periodic
from ..effects.simulator_only import MarkovNoise

MODELS = ("bias-t", "thermal", "composite", "allan")

#: Effects the loop may add to each base model (None: every registered effect, read at call
#: time by :func:`allowed`, so an effect registered at runtime reaches the loop).
ALLOWED: dict[str, tuple[str, ...] | None] = {
    "bias-t": None,
    "thermal": None,
    "composite": None,
    "allan": (MarkovNoise.name, Periodic.name),
}


def allowed(model: str) -> tuple[str, ...]:
    """The effect names the loop may add to ``model``, in registry order."""
    names = ALLOWED[model]
    return tuple(REGISTRY) if names is None else names


class ModelNameError(FogbayesError):
    """An unknown base model name or malformed orders."""


def _tscale(ctx: Context) -> tuple[float, float]:
    T = ctx.cov.T[:, 0]
    return 0.5 * (float(T.max()) + float(T.min())), max(0.5 * float(np.ptp(T)), 1e-3)


def _need_temperature(ctx: Context, model: str, source) -> None:
    if ctx.cov.n_temps == 0:
        raise MissingColumnError(f"model '{model}' needs a temperature channel", file=source,
                                 column="temperature",
                                 fix="add a 'temperature' column (deg C) or use --model allan")


def parse_orders(model: str, orders: str | None) -> tuple[int, ...]:
    """Orders for a base model: bias-t "n" (T order); thermal "n" or "n,m" (T order, dT/dt
    order; "n" sets both, as ``fogbayes fit``); composite "s1,s2,u0[,u1]"."""
    if orders is None:
        if model in DEFAULT_ORDERS:  # ``fogbayes fit``'s defaults: one table
            orders = DEFAULT_ORDERS[model]
        else:
            return {"composite": (0, 0, 2, None), "allan": ()}[model]
    if model == "composite":
        try:
            return read_orders(orders)
        except OrdersError as e:
            raise ModelNameError(e.problem, column="orders",
                                 fix=e.fix) from None
    try:
        vals = tuple(int(v) for v in str(orders).split(","))
    except ValueError:
        vals = ()
    ok = (len(vals) == 1 if model == "bias-t" else len(vals) in (1, 2) if model == "thermal"
          else len(vals) == 0)
    if not ok or any(v < 0 or v > 6 for v in vals):
        raise ModelNameError(f"orders {orders!r} do not fit model '{model}'", column="orders",
                             fix="bias-t: one integer (e.g. 2); thermal: n or n,m (T, dT/dt; "
                                 "e.g. 2,1); composite: s1,s2,u0[,u1] (e.g. 0,0,2,-); allan: none")
    return vals * 2 if model == "thermal" and len(vals) == 1 else vals


def base_terms(ctx: Context, model: str, orders: str | None = None, *, source=None) -> list[Term]:
    """The term list of base ``model`` on this recording."""
    if model not in MODELS:
        raise ModelNameError(f"unknown model '{model}'", flag="--model",
                             fix=f"use one of {', '.join(MODELS)}")
    o = parse_orders(model, orders)
    terms = [Term("intercept", {"effect": "base"})]
    if model == "allan":
        return terms
    _need_temperature(ctx, model, source)
    c, s = _tscale(ctx)
    varies = float(np.ptp(ctx.cov.T[:, 0])) >= 0.1  # deg C; a soaked record has no T law
    if model in ("bias-t", "thermal"):
        if o[0] > 0 and varies:
            terms.append(Term("tpoly", {"effect": "base", "channel": 0,
                                        "powers": list(range(1, o[0] + 1)), "centre": c, "scale": s}))
        if model == "thermal" and o[1] > 0:
            rs = max(float(np.max(np.abs(ctx.cov.Tdot))), 1e-3)
            terms.append(Term("rate_poly", {"effect": "base", "powers": list(range(1, o[1] + 1)),
                                            "scale": rs}))
        return terms
    if ctx.cov.omega is None:
        raise MissingColumnError("model 'composite' needs the reference input rate", file=source,
                                 column="input_rate", fix="add an 'input_rate' column (deg/s)")
    s1, s2, u0 = o[:3]
    ws = max(float(np.max(np.abs(ctx.cov.omega))), 1e-9)
    # S1(T) S2(W) W linearised: every T'^i W'^(j+1), i <= s1, j <= s2 (paper 000's full M)
    terms.append(Term("omega_poly", {"effect": "base", "powers": list(range(1, s2 + 2)),
                                     "scale": ws}))
    for i in range(1, s1 + 1 if varies else 1):
        for j in range(s2 + 1):
            terms.append(Term("omega_tpoly", {"effect": "base", "channel": 0, "powers": [i],
                                              "wpower": j + 1, "centre": c, "t_scale": s,
                                              "scale": ws}))
    if u0 > 0 and varies:
        terms.append(Term("tpoly", {"effect": "base", "channel": 0,
                                    "powers": list(range(1, u0 + 1)), "centre": c, "scale": s}))
    if o[3] is not None and varies:
        op = ctx.cov.op_time if ctx.cov.op_time is not None else ctx.cov.t
        terms.append(Term("drift_tpoly", {"effect": "base", "channel": 0,
                                          "powers": list(range(o[3] + 1)), "centre": c,
                                          "scale": s, "duration": max(float(np.max(op)), 1.0)}))
    return terms
