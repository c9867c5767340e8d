"""Warnings when a record cannot tell the loop's drivers apart (said, never silent).

r = corr(T_b, t_b) over the observed blocks; |r| >= R_WARN (0.99) warns that a T law, a drift
and a warm-up explain the same residual.
"""

from __future__ import annotations

import numpy as np

R_WARN = 0.99


def collinearity_warnings(ctx) -> list[str]:
    """Plain-language warnings for drivers the record cannot separate (see module doc)."""
    cov, ok = ctx.bcov, ctx.grid.mask > 0
    if cov.n_temps == 0 or ok.sum() < 3:
        return []
    out = []
    t = cov.t[ok]
    for j, name in enumerate(cov.names):
        T = cov.T[ok, j]
        if np.ptp(T) <= 0 or np.ptp(t) <= 0:
            continue
        r = float(np.corrcoef(T, t)[0, 1])
        if abs(r) >= R_WARN:
            out.append(f"temperature '{name}' and time are correlated at r = {r:.4f}: a "
                       "temperature law and a time drift or warm-up cannot be told apart on "
                       "this record (record heating and cooling, or a soak, to separate them)")
    return out
