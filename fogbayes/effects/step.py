"""step: b = size for t >= time, else 0; searched at every block boundary in 2-98 % of
the record."""

from __future__ import annotations

import numpy as np

from .terms import Term
from .base import Candidate, Effect, count, e


class Step(Effect):
    name = "step"
    what = "a step"
    applies = "run"
    description = "bias step of `size` deg/h at `time` s (default: mid-record)"
    defaults = {"time": None, "size": 0.2}
    size_keys = ("size",)
    max_times = 3

    def plant(self, p):
        return [(Term("step", {"time": p["time"]}), [p["size"]])]

    def complete(self, p, cov):
        if p["time"] is None:
            p["time"] = float(cov.time[0] + 0.5 * (cov.time[-1] - cov.time[0]))
        return p

    def oracle(self, ctx, p):
        return [Term("step", {"time": p.get("time", 0.0)})]

    def candidates(self, ctx, terms):
        if count(terms, self.name) >= self.max_times:
            return []
        obs = np.flatnonzero(ctx.grid.mask > 0)
        lo, hi = obs[max(1, int(0.02 * obs.size))], obs[min(obs.size - 2, int(0.98 * obs.size))]
        pos = np.arange(lo, hi + 1)  # every block boundary (module doc)
        times = ctx.grid.t[pos] - 0.5 * ctx.grid.dt  # block boundaries
        return [Candidate("step", "linear", tuple(
            Term("step", e("step", time=float(tm))) for tm in times), ("time",), "time")]
