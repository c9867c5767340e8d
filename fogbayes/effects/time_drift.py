"""time_drift: b = s t/3600 + A (1 - exp(-t/tau)), a drift and a warm-up since the first sample."""

from __future__ import annotations

import numpy as np

from .terms import Term
from .base import Candidate, Effect, count, e


class TimeDrift(Effect):
    name = "time_drift"
    what = "a warm-up or drift"
    remedy = ("start the programme with a constant-temperature soak of a few warm-up "
              "time constants before the first ramp (fogbayes plan-chamber scores "
              "programmes)")
    description = "s t/3600 + A (1 - exp(-t/tau)): drift and warm-up (deg/h)"
    defaults = {"slope": 0.0, "amplitude": 1.0, "tau": 5400.0}
    size_keys = ("amplitude", "slope")
    max_times = 2

    def plant(self, p):
        return [(Term("drift_lin", {"duration": 3600.0}), [p["slope"]]),
                (Term("intercept", {}), [p["amplitude"]]),
                (Term("drift_exp", {"tau": p["tau"]}), [-p["amplitude"]])]

    def oracle(self, ctx, p):
        return [Term("drift_exp", {"tau": p.get("tau", 5400.0)})] + (
            [Term("drift_lin", {"duration": ctx.cov.duration})] if p.get("slope") else [])

    def candidates(self, ctx, terms):
        if count(terms, self.name) >= self.max_times:
            return []
        dur = ctx.cov.duration
        have = {tm.kind for tm in terms if tm.params.get("effect") == "time_drift"}
        grid = [] if "drift_lin" in have else [Term("drift_lin", e("time_drift", duration=dur))]
        if "drift_exp" not in have:
            grid += [Term("drift_exp", e("time_drift", tau=float(tau)))
                     for tau in np.geomspace(dur / 100.0, dur, 10)]
        if not grid:
            return []
        return [Candidate("time_drift", "linear", tuple(grid), ("time",), "tau")]
