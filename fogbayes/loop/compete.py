"""Rank two candidate effects that explain the same residual against each other (Cox test by simulation).

On the whitened, X-projected block residual r, each at its best grid value:
RSS_C = min_g (||r||^2 - ||Q_g' r||^2), D = n_obs log(RSS_A / RSS_B); the noise is the REML
model of X + A + B. p_A = P*(D* >= D | A), p_B = P*(D* <= D | B) by parametric bootstrap with
both grids searched again. One rejected: the other wins; neither: *indistinguishable*, the
simpler kept; both: decided by held-out prediction (:mod:`fogbayes.loop.ranking`).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from .candidates import Candidate
from .context import Context
from .evidence import Screened, Whitened, _basis, whitened_model
from .fitting import ModelFit, fit_terms
from .refine import _local_terms
from .reml import with_reml
from ..effects.terms import Term, columns

LEVEL = 0.05


class Duel(NamedTuple):
    """Outcome of A (the leader) against B: ``winner`` is "A" or "B"; ``verdict`` says why."""

    d_obs: float          # 2 logL(X + B) - 2 logL(X + A) at the shared noise model
    p_a: float            # bootstrap P(D* >= d_obs | A is the effect)
    p_b: float            # bootstrap P(D* <= d_obs | B is the effect)
    winner: str
    verdict: str          # "A better", "B better", "indistinguishable", "neither alone"
    n_sims: int
    lpd: tuple[float, float] | None = None  # held-out lpd of (A, B), where it decided


def n_searched(c: Candidate) -> int:
    """Searched parameters of a candidate: 0 for a fixed column, 1 for a grid."""
    return 0 if c.searched is None else 1


def _grid_terms(ctx: Context, s: Screened, best: Term) -> list[Term]:
    """The candidate's grid, refined around the data's optimum as the added term was.

    The added term's searched value was refined on a fine local grid; the bootstrap must
    search as finely, or the data's D (refined) is compared with simulated D's on a coarser
    grid -- measured: p-values under the truth then fall below 0.05 five times as often.
    """
    grid = list(s.candidate.grid)
    if s.best is not None and s.candidate.searched is not None:
        grid += [t for t in _local_terms(ctx, s) if t not in grid]
    return grid + [best] if best is not None and best not in grid else grid


def _projected_bases(wm: Whitened, Zw: np.ndarray, ks: list[int]) -> list[np.ndarray]:
    out, j = [], 0
    for k in ks:
        Q = _basis(Zw[:, j:j + k], wm.Qx)
        j += k
        if Q is not None:
            out.append(Q)
    return out


def _max_explained(bases: list[np.ndarray], R: np.ndarray) -> np.ndarray:
    """max over the grid of ||Q_g' R||^2 for every column of R (n_obs, B) -> (B,)."""
    best = np.zeros(R.shape[1])
    ones = [Q[:, 0] for Q in bases if Q.shape[1] == 1]
    if ones:
        best = np.maximum(best, np.max((np.column_stack(ones).T @ R) ** 2, axis=0))
    for Q in bases:
        if Q.shape[1] > 1:
            best = np.maximum(best, np.sum((Q.T @ R) ** 2, axis=0))
    return best


def _d(bases_a, bases_b, R: np.ndarray, n_obs: int) -> np.ndarray:
    tot = np.sum(R * R, axis=0)
    rss_a = np.maximum(tot - _max_explained(bases_a, R), 1e-300)
    rss_b = np.maximum(tot - _max_explained(bases_b, R), 1e-300)
    return n_obs * np.log(rss_a / rss_b)


def _fitted_signal(Q: np.ndarray, r: np.ndarray, dof: int) -> tuple[np.ndarray, float]:
    """Projection of r on Q (the fitted effect) and the residual variance of that model."""
    sig = Q @ (Q.T @ r)
    res = r - sig
    return sig, float(res @ res / max(dof - Q.shape[1], 1))


def _best_basis(bases, r):
    expl = [float(np.sum((Q.T @ r) ** 2)) for Q in bases]
    return bases[int(np.argmax(expl))]


def bootstrap_p(qa: list[np.ndarray], qb: list[np.ndarray], r: np.ndarray, E: np.ndarray,
                dof: int, under: str) -> tuple[float, float]:
    """D of the whitened residual ``r`` and its bootstrap p-value under hypothesis ``under``.

    qa, qb: orthonormal bases (design projected out) of every grid point of A and B;
    r (n_obs,): whitened, design-projected residual; E (n_obs, B): whitened unit-variance
    null series projected the same way; dof: n_obs - design columns. Under "A" the p-value
    is P*(D* >= D), under "B" P*(D* <= D) (see the module doc).
    """
    n_obs = r.size
    d_obs = float(_d(qa, qb, r[:, None], n_obs)[0])
    # the fitted effect under the hypothesis, plus whitened null noise at its variance
    sig, s2 = _fitted_signal(_best_basis(qa if under == "A" else qb, r), r, dof)
    d_sim = _d(qa, qb, sig[:, None] + math.sqrt(s2) * E, n_obs)
    hits = np.sum(d_sim >= d_obs) if under == "A" else np.sum(d_sim <= d_obs)
    return d_obs, float((1 + hits) / (1 + d_sim.size))


def _encompassing(ctx: Context, fit: ModelFit, a: ModelFit, b: ModelFit) -> ModelFit:
    """X + A + B refitted (ML, then REML noise): the noise model both hypotheses share.

    If either candidate is the effect this model is correct, so its noise estimate is
    consistent under both; a candidate's own refit is not -- a wrong candidate's misfit
    is taken up by its noise model (measured: a random walk 250 times larger under a
    wrong scale-factor term, which flipped the sign of D). A failed fit (collinear
    candidates) falls back to the better-likelihood refit.
    """
    best = a if a.loglik >= b.loglik else b
    try:
        enc = fit_terms(ctx, tuple(fit.terms) + (a.terms[-1], b.terms[-1]), spec=best.noise.spec,
                        theta0=best.noise.theta, residual=False)
    except (np.linalg.LinAlgError, FloatingPointError, ValueError):
        return best
    return enc if np.isfinite(enc.loglik) and enc.loglik >= best.loglik - 1e-6 else best


def duel(ctx: Context, fit: ModelFit, a: tuple[Screened, ModelFit], b: tuple[Screened, ModelFit],
         *, n_sims: int = 300, seed: int = 0, level: float = LEVEL,
         cache: dict | None = None) -> Duel | None:
    """Compare candidate ``a`` (the leader) with ``b`` (see module doc); None if not comparable.

    ``fit`` is the current model (without either); ``a``/``b`` are (screened, refitted
    model with the candidate added): the refits give the refined terms, and the model with
    both gives the shared noise (REML, :mod:`fogbayes.loop.reml`).
    """
    ta = _grid_terms(ctx, a[0], a[1].terms[-1])
    tb = _grid_terms(ctx, b[0], b[1].terms[-1])
    Za = [columns(t, ctx.bcov) for t in ta]
    Zb = [columns(t, ctx.bcov) for t in tb]
    noise = with_reml(ctx, _encompassing(ctx, fit, a[1], b[1]), cache).noise
    wm, Zw = whitened_model(ctx, fit._replace(noise=noise), n_sims=n_sims, seed=seed,
                            extra=np.column_stack(Za + Zb))
    ka, kb = [z.shape[1] for z in Za], [z.shape[1] for z in Zb]
    qa = _projected_bases(wm, Zw[:, :sum(ka)], ka)
    qb = _projected_bases(wm, Zw[:, sum(ka):], kb)
    if not qa or not qb:
        return None
    dof = wm.r.size - wm.Qx.shape[1]
    d_obs, p_a = bootstrap_p(qa, qb, wm.r, wm.E, dof, "A")
    _, p_b = bootstrap_p(qa, qb, wm.r, wm.E, dof, "B")
    B = wm.E.shape[1]
    rej_a, rej_b = p_a < level, p_b < level
    if rej_a and not rej_b:
        return Duel(d_obs, p_a, p_b, "B", "B better", B)
    if rej_b and not rej_a:
        return Duel(d_obs, p_a, p_b, "A", "A better", B)
    if not rej_a and not rej_b:
        ca, cb = n_searched(a[0].candidate), n_searched(b[0].candidate)
        return Duel(d_obs, p_a, p_b, "B" if cb < ca else "A", "indistinguishable", B)
    return Duel(d_obs, p_a, p_b, "B" if d_obs > 0 else "A", "neither alone", B)
