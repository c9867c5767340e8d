"""Refine a screened candidate's searched parameter between its grid neighbours.

Maximises the fixed-noise statistic of :mod:`fogbayes.loop.evidence` on a fine local grid:
block boundaries (step), 25 log-spaced values (tau, r0), 41 frequencies within +-1 FFT bin.
After the decision, :func:`polish_step` places a step to 1/20 block and :func:`polish` re-scores
a scale (ratio 1.5 each side, up to :data:`RECENTRE_ROUNDS` re-centrings) under the refit's
noise; each is kept only if the refitted likelihood rises.
"""

from __future__ import annotations

import numpy as np

from .context import Context
from .evidence import Screened, Whitened, _basis, whiten_columns, whitened_model
from .fitting import ModelFit, fit_terms
from ..effects.kinds import KINDS, Periodic, Step, kind_of
from ..effects.terms import Term, columns

#: sub-block positions per block tried by :func:`polish_step`
STEP_SUBDIVISIONS = 20
#: searched scale of each term kind that :func:`polish` re-scores (``Kind.scale_key``)
SCALES = {k: v.scale_key for k, v in KINDS.items() if v.scale_key}
#: times the scale grid is re-centred while its best value is at an edge
RECENTRE_ROUNDS = 4
#: most refits :func:`polish` makes while the scale keeps moving
POLISH_ROUNDS = 4


def _with(term: Term, **changes) -> Term:
    return Term(term.kind, {**term.params, **changes})


def _local_terms(ctx: Context, s: Screened) -> list[Term]:
    term, grid = s.best, s.candidate.grid
    k = term.kind
    if k == Step.name:
        times = np.array([g.params["time"] for g in grid])
        i = int(np.argmin(np.abs(times - term.params["time"])))
        lo = times[max(i - 1, 0)]
        hi = times[min(i + 1, times.size - 1)]
        edges = ctx.grid.t - 0.5 * ctx.grid.dt
        sel = edges[(edges >= lo) & (edges <= hi)]
        return [_with(term, time=float(t)) for t in sel]
    key = kind_of(k).scale_key
    if key is not None:
        vals = np.array(sorted(g.params[key] for g in grid if g.kind == k))
        v = term.params[key]
        i = int(np.argmin(np.abs(np.log(vals / v))))
        lo = vals[max(i - 1, 0)] if i > 0 else v / 2.0
        hi = vals[min(i + 1, vals.size - 1)] if i < vals.size - 1 else v * 2.0
        return [_with(term, **{key: float(x)}) for x in np.geomspace(lo, hi, 25)]
    if k == Periodic.name:
        df = 1.0 / (2 * ctx.grid.n * ctx.grid.dt)
        f = term.params["frequency"]
        return [_with(term, frequency=float(x)) for x in np.linspace(f - df, f + df, 41)]
    return [term]


def local_stats(ctx: Context, wm: Whitened, terms: list[Term], *,
                exact: bool = False) -> np.ndarray:
    """Fixed-noise 2 dlogL of each term added alone to the whitened model.

    exact: the block means of the per-sample columns (``Context.block_columns``) instead
    of the columns of the block-mean covariates (what the screening uses).
    """
    Z = [ctx.block_columns(t) if exact else columns(t, ctx.bcov) for t in terms]
    Zw = whiten_columns(ctx, wm.spec, wm.theta, np.column_stack(Z))
    out, j = [], 0
    for z in Z:
        k = z.shape[1]
        Q = _basis(Zw[:, j:j + k], wm.Qx)
        j += k
        out.append(-np.inf if Q is None else float(np.sum((Q.T @ wm.r) ** 2) / wm.s2))
    return np.array(out)


def refine(ctx: Context, wm: Whitened, s: Screened) -> tuple[Term, float]:
    """The best term near the screened optimum and its fixed-noise statistic."""
    terms = _local_terms(ctx, s)
    if len(terms) <= 1:
        return s.best, s.stat
    st = local_stats(ctx, wm, terms)
    b = int(np.argmax(st))
    if not np.isfinite(st[b]) or st[b] < s.stat:
        return s.best, s.stat
    return terms[b], float(st[b])


def _whitened_under(ctx: Context, base: ModelFit, alt: ModelFit) -> Whitened:
    """``base``'s design whitened under ``alt``'s noise: where the polish scores its terms."""
    return whitened_model(ctx, base._replace(noise=alt.noise), n_sims=0, seed=0)[0]


def _refit_if_better(ctx: Context, base: ModelFit, alt: ModelFit, term: Term) -> ModelFit:
    """``base`` + ``term`` refitted from ``alt``'s noise; ``alt`` unless the likelihood rises."""
    new = fit_terms(ctx, base.terms + (term,), spec=alt.noise.spec, theta0=alt.noise.theta)
    return new if new.loglik > alt.loglik else alt


def polish_step(ctx: Context, base: ModelFit, alt: ModelFit) -> ModelFit:
    """``alt`` (``base`` + a step as its last term) with the step time placed within a block.

    Times from one block before to one block after the accepted time, every
    1/:data:`STEP_SUBDIVISIONS` of a block, scored by the fixed-noise statistic on the exact
    block columns under ``alt``'s noise; the best is refitted and kept if the likelihood
    rises (module doc). Any other last term: ``alt`` unchanged.
    """
    term = alt.terms[-1]
    if term.kind != Step.name:
        return alt
    dt = ctx.grid.dt
    offsets = dt * np.linspace(-1.0, 1.0, 2 * STEP_SUBDIVISIONS + 1)
    terms = [_with(term, time=float(term.params["time"] + o)) for o in offsets]
    st = local_stats(ctx, _whitened_under(ctx, base, alt), terms, exact=True)
    b = int(np.argmax(st))
    if not np.isfinite(st[b]) or offsets[b] == 0.0:
        return alt
    return _refit_if_better(ctx, base, alt, terms[b])


def polish_scale(ctx: Context, base: ModelFit, alt: ModelFit) -> ModelFit:
    """``alt`` with its last term's searched scale re-scored under ``alt``'s noise (module doc).

    Any term without a scale (``Kind.scale_key``): ``alt`` unchanged.
    """
    term = alt.terms[-1]
    key = kind_of(term.kind).scale_key
    if key is None:
        return alt
    wm = _whitened_under(ctx, base, alt)
    v0 = v = float(term.params[key])
    for _ in range(RECENTRE_ROUNDS):
        vals = np.geomspace(v / 1.5, v * 1.5, 25)
        st = local_stats(ctx, wm, [_with(term, **{key: float(x)}) for x in vals], exact=True)
        b = int(np.argmax(st))
        if not np.isfinite(st[b]):
            break
        v = float(vals[b])
        if 0 < b < vals.size - 1:
            break
    if v == v0:
        return alt
    return _refit_if_better(ctx, base, alt, _with(term, **{key: v}))


def polish(ctx: Context, base: ModelFit, alt: ModelFit) -> ModelFit:
    """An accepted term placed after the decision: a step's time, or a searched scale.

    The scale is re-scored until it stops moving (at most :data:`POLISH_ROUNDS` refits):
    each refit's noise is closer to the one the right scale implies.
    """
    out = polish_step(ctx, base, alt)
    for _ in range(POLISH_ROUNDS):
        new = polish_scale(ctx, base, out)
        if new is out:
            break
        out = new
    return out
