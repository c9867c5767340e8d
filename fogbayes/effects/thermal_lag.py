"""thermal_lag: b = k (L - T_ref), tau dL/dt = T - L (L starts in equilibrium with T)."""

from __future__ import annotations

import numpy as np

from .terms import Term
from .base import Candidate, Effect, e, moving, thermal, tscale


class ThermalLag(Effect):
    name = "thermal_lag"
    what = "a thermal lag"
    description = "k (T_lag - T_ref), T_lag = T through a first-order lag tau (s)"
    defaults = {"coeff": 0.01, "tau": 1800.0, "T_ref": 20.0}
    size_keys = ("coeff",)
    separable_by_programme = True
    processing = {"lag": "first-order lag started at the first sample's temperature"}

    def plant(self, p):
        return [(Term("lag", {"channel": 0, "tau": p["tau"], "centre": p["T_ref"],
                              "scale": 1.0}), [p["coeff"]])]

    def programme_terms(self, ctx, n, true=None):
        """Unit-scale lags centred on the record's mid temperature: at ``true["tau"]``, or
        ``n`` time constants log-spaced over the loop's range."""
        taus = [true["tau"]] if true and "tau" in true else np.geomspace(*_tau_range(ctx), n)
        centre, _ = tscale(ctx)
        return [self.plant({**self.defaults, "tau": float(tau), "T_ref": centre})[0][0]
                for tau in taus]

    def oracle(self, ctx, p):
        c, s = tscale(ctx)
        return [Term("lag", {"channel": 0, "tau": p.get("tau", 1800.0), "centre": c,
                             "scale": s})]

    def candidates(self, ctx, terms):
        if not thermal(ctx) or not moving(ctx) or "lag" in {tm.kind for tm in terms}:
            return []
        lo, hi = _tau_range(ctx)
        if hi <= 2 * lo:
            return []
        centre, scale = tscale(ctx)
        return [Candidate("thermal_lag", "linear", tuple(
            Term("lag", e("thermal_lag", channel=0, tau=float(tau), centre=centre, scale=scale))
            for tau in np.geomspace(lo, hi, 12)), ("temperature",), "tau")]


def _tau_range(ctx) -> tuple[float, float]:
    """The searched time constants (s): from 60 s (or 3 blocks) to half the record."""
    return max(60.0, 3 * ctx.grid.dt), 0.5 * ctx.cov.duration
