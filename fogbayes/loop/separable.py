"""What the record's programme and noise let the loop see: effects it cannot separate.

Under the base noise, with M projecting out the whitened base: share = 1 - ||M z~||^2 / ||z~||^2,
se = sqrt(s2) / ||M z~||, detectable peak d = (z_{1-a/2} + z_{0.8}) se max|z|, a = alpha /
(candidates x grid points). Confounded: share >= :data:`SHARE_WARN` at every grid value; a step
whose d the random walk more than doubles says so. Rows go to ``detectable``; warnings name
the effect, the unseen size and the remedy.
"""

from __future__ import annotations

import numpy as np

from ..support.tails import norm_isf, norm_ppf
from . import evidence as ev
from .candidates import candidates_for
from .context import Context
from .fitting import ModelFit
from ..effects.terms import columns
from ..effects import REGISTRY
from ..inference import noise_ssm as ns

#: share of an effect the base already fits beyond which it is reported as confounded
SHARE_WARN = 0.9
#: the walk "hides" steps when it multiplies their detectable size by more than this
WALK_WARN = 2.0
POWER_Z = norm_ppf(0.8)
#: grid points examined per searched candidate (evenly spaced over its grid)
MAX_GRID = 12

REMEDY_WALK = ("a static run's noise prior caps the walk (fogbayes allan static.csv --json "
               "static.json, then fogbayes loop --noise-prior static.json)")
REMEDY_DEFAULT = ("a programme that moves this driver apart from the base's (ramps at two "
                  "rates, heating and cooling, soaks between; fogbayes plan-chamber)")


def _searched(term) -> str:
    p = term.params
    for key, unit in (("tau", "s"), ("time", "s"), ("r0", "deg C/min"), ("width", "deg C"),
                      ("channel", "")):
        if key in p:
            v = p[key]
            return f"{key} {float(v):.4g} {unit}" if unit else f"{key} {v}"
    return ""


def _points(cand):
    grid = [tm for tm in cand.grid if tm.n_cols == 1]
    if len(grid) > MAX_GRID:
        grid = [grid[i] for i in np.linspace(0, len(grid) - 1, MAX_GRID).round().astype(int)]
    return grid


def detectable_sizes(ctx: Context, spec, theta, s2: float, X: np.ndarray, Z: np.ndarray, a: float):
    """(share, detectable peak size deg/h) of each column of block-level Z against X."""
    W = ev.whiten_columns(ctx, spec, theta, np.column_stack([X, Z]))
    p = X.shape[1]
    Q, _ = np.linalg.qr(W[:, :p])
    Zw = W[:, p:]
    Zp = Zw - Q @ (Q.T @ Zw)
    nz, nzp = np.linalg.norm(Zw, axis=0), np.linalg.norm(Zp, axis=0)
    share = 1.0 - (nzp / np.maximum(nz, 1e-300)) ** 2
    peak = np.max(np.abs(Z), axis=0)
    z = norm_isf(a / 2.0) + POWER_Z
    d = z * np.sqrt(s2) / np.maximum(nzp, 1e-300) * peak
    return share, d


LABEL = {"intercept": "constant", "tpoly": "temperature law", "rate_poly": "dT/dt terms",
         "omega_poly": "scale factor"}


def _base_name(ctx: Context, fit: ModelFit, z_block: np.ndarray, spec, theta) -> str:
    """The base terms the candidate column needs: those whose removal frees at least a
    tenth of it (else the one that frees the most)."""
    freed, col = [], 0
    for tm in fit.terms:
        k = tm.n_cols
        keep = [j for j in range(fit.X.shape[1]) if not col <= j < col + k]
        col += k
        if keep:
            share, _ = detectable_sizes(ctx, spec, theta, 1.0, fit.X[:, keep],
                                        z_block[:, None], 0.05)
            freed.append((1.0 - float(share[0]), LABEL.get(tm.kind, tm.kind)))
    if not freed:
        return "the base model"
    names = [n for f, n in freed if f >= 0.1] or [max(freed)[1]]
    return " and ".join(dict.fromkeys(names))


def detectability(ctx: Context, fit: ModelFit, alpha: float, effects=None) -> list[dict]:
    """One row per candidate effect: the largest size (deg/h, over its searched grid) that
    could go unseen, with and without the walk, and how much of it the base already fits
    under the noise without the walk (the programme's part; module doc)."""
    cands = [c for c in candidates_for(ctx, fit.terms, effects=effects)
             if c.kind == "linear" and REGISTRY[c.effect].what]
    if not cands:
        return []
    nf = fit.noise
    pts = [(c, _points(c)) for c in cands]
    pts = [(c, g) for c, g in pts if g]
    a = alpha / max(sum(len(g) for _, g in pts), 1)
    Z = np.column_stack([columns(tm, ctx.bcov) for _, g in pts for tm in g])
    _, d = detectable_sizes(ctx, nf.spec, nf.theta, nf.sigma2, fit.X, Z, a)
    spec0, theta0 = nf.spec, nf.theta
    if nf.spec.random_walk:
        spec0 = nf.spec._replace(random_walk=False)
        theta0 = ns.pack(spec0, ns.unpack(nf.spec, nf.theta))
    share, d0 = detectable_sizes(ctx, spec0, theta0, nf.sigma2, fit.X, Z, a)
    rows, j = [], 0
    for c, grid in pts:
        sl = slice(j, j + len(grid))
        j += len(grid)
        k = int(np.argmax(d[sl]))
        ks = int(np.argmax(d0[sl]))  # the grid point the programme hides best
        rows.append({"effect": c.effect, "at": _searched(grid[k]),
                     "detectable_deg_h": float(d[sl][k]),
                     "detectable_without_walk_deg_h": float(d0[sl][k]),
                     "share_fitted_by_base": float(share[sl][ks]),
                     "share_at": _searched(grid[ks]),
                     "share_min_over_grid": float(np.min(share[sl])),
                     # confounded: no value of its searched parameter sets it apart
                     "confounded_with": (_base_name(ctx, fit, Z[:, sl][:, ks], spec0, theta0)
                                         if np.min(share[sl]) >= SHARE_WARN else None)})
    return rows


def separability_warnings(rows: list[dict], rms: float) -> list[str]:
    """Plain-language warnings from :func:`detectability`'s rows: effects the programme
    confounds with the base, and the slow effects the random walk hides, where the size
    that could go unseen exceeds ``rms`` (the base fit's residual 10 s RMS, deg/h)."""
    out, walk = [], []
    for r in rows:
        d, d0 = r["detectable_deg_h"], r["detectable_without_walk_deg_h"]
        if r["confounded_with"] and d0 > rms:
            at = f", {r['share_at']}" if r["share_at"] else ""
            size = "any size" if d0 > 1e6 * rms else f"up to {d0:.3g} deg/h"
            what = REGISTRY[r["effect"]].what
            out.append(f"{what} ({r['effect']}{at}) cannot be told apart from "
                       f"the base's {r['confounded_with']} on this programme "
                       f"({100 * r['share_fitted_by_base']:.0f} % of it is what the base "
                       f"fits): one of {size} would go unseen, fitted as the "
                       f"{r['confounded_with']} and carried so to runs under another "
                       f"programme; remedy: "
                       f"{REGISTRY[r['effect']].remedy or REMEDY_DEFAULT}")
        elif d > WALK_WARN * d0 and d > rms:
            walk.append(r)
    if walk:
        walk.sort(key=lambda r: -r["detectable_deg_h"])
        sizes = "; ".join(f"{REGISTRY[r['effect']].what} ({r['effect']}) up to "
                          f"{r['detectable_deg_h']:.3g} deg/h "
                          f"({r['detectable_without_walk_deg_h']:.3g} without the walk)"
                          for r in walk)
        out.append(f"this record's random walk hides slow effects larger than its residual "
                   f"10 s RMS ({rms:.3g} deg/h): {sizes} could go unseen; remedy: "
                   f"{REMEDY_WALK}")
    return out
