"""Time-blocked cross-validation: does a model predict blocks it was not fitted on?

K = 10 contiguous folds; per fold, beta_(-k) by GLS on the others (theta, s2 fixed) and
lpd_k = log p(y; beta_(-k)) - log p(y_(-k); beta_(-k)) (two Kalman passes), lpd = sum_k lpd_k.
:func:`compare` keeps a term if lpd with it >= without it (se = sqrt(K' var(d_k)) reported;
strict rule: benchmarks/RESULTS_loop_real.md). Folds where the others carry less than
:data:`MIN_INFORMATION` of a new coefficient's information are left out; a step's time is
re-chosen per fold (:func:`searched_columns`, :mod:`.holdout_search`).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from .context import Context
from .fitting import ModelFit
from ..effects import kinds
from ..effects.step import Step
from ..inference import noise_ssm as ns
from .holdout_search import fold_lpd

N_FOLDS = 10
#: least share of a new coefficient's information the other folds must hold (module doc)
MIN_INFORMATION = 0.1


class Holdout(NamedTuple):
    lpd: float            # nats, summed over folds (module doc)
    per_fold: np.ndarray  # lpd_k
    n_blocks: int         # observed blocks scored
    info: np.ndarray      # (K, p) share of each coefficient's information outside fold k


def folds(ctx: Context, k: int = N_FOLDS) -> np.ndarray:
    """Fold index of every block: K contiguous runs of equal numbers of observed blocks."""
    obs = ctx.grid.mask > 0
    rank = np.cumsum(obs) - 1
    n = int(obs.sum())
    return np.clip(rank * k // max(n, 1), 0, k - 1)


def _loglik(V: np.ndarray, F: np.ndarray, beta: np.ndarray, s2: float, m: np.ndarray) -> float:
    r = V[m, 0] - V[m, 1:] @ beta
    f = s2 * F[m]
    return float(-0.5 * np.sum(np.log(2.0 * math.pi * f) + r * r / f))


def score(ctx: Context, fit: ModelFit, k: int = N_FOLDS, *, ols: bool = False,
          search: np.ndarray | None = None) -> Holdout:
    """The held-out predictive density of ``fit`` (module doc); ``ols``: the coefficients of
    each fold by least squares (weights 1 / w) instead of GLS -- the plain ``fogbayes fit``'s
    estimator -- scored under ``fit``'s noise model all the same. ``search`` (nb, G): block
    columns of the grid of the last term's searched parameter; each fold then averages
    over that grid as its training blocks weigh it (:mod:`.holdout_search`) instead of
    taking the value the whole record chose."""
    spec, theta, s2 = fit.noise.spec, fit.noise.theta, float(fit.noise.sigma2)
    mask, w = np.asarray(ctx.grid.mask, float), ctx.grid.w
    p = fit.X.shape[1]
    # y less its least-squares fit on the columns every fold's model holds (all of them;
    # all but the searched last one with ``search``): the filter is linear in each column,
    # so every fold's residual is the same, and its quadratic forms are of the residual's
    # size instead of the signal's (noise_ssm's module doc, "Precision": a rate table's
    # output is ~1e6 times its noise). ``fit.beta`` may belong to other terms (the plain
    # fit's check scores its own terms under the final fit's noise).
    keep = p - 1 if search is not None else p
    obs = mask > 0
    y = np.where(obs, ctx.y, 0.0)
    if keep > 0:
        y = y - fit.X[:, :keep] @ np.linalg.lstsq(fit.X[obs, :keep], y[obs], rcond=None)[0]
    Y = np.column_stack([np.where(obs, y, 0.0), fit.X])
    if search is not None:  # [y, the rest of the model, the grid] after the fitted columns
        Y = np.column_stack([Y, Y[:, :p], search])
    V_all, F_all = ns.filter_padded(spec, theta, Y, mask, w)
    _, _, cov_all, s2_all = ns.profile_np(V_all[:, :p + 1], F_all, mask)
    var_all = np.diag(cov_all) / s2_all
    fid = folds(ctx, k)
    per = np.zeros(k)
    info = np.ones((k, fit.X.shape[1]))
    for j in range(k):
        held = (fid == j) & (mask > 0)
        if not held.any():
            continue
        train = np.where(held, 0.0, mask)
        V, F = ns.filter_padded(spec, theta, Y, train, w)
        _, beta, cov, s2_tr = ns.profile_np(V[:, :p + 1], F, train)
        info[j] = var_all / np.maximum(np.diag(cov) / s2_tr, 1e-300)
        if search is not None:
            per[j] = fold_lpd(V[:, p + 1:], F, train, V_all[:, p + 1:], F_all, mask, p, s2)
            continue
        if ols:
            sw = np.sqrt(train / np.asarray(w, float))
            beta = np.linalg.lstsq(fit.X * sw[:, None], Y[:, 0] * sw, rcond=None)[0]
        per[j] = (_loglik(V_all, F_all, beta, s2, mask > 0)
                  - _loglik(V, F, beta, s2, train > 0))
    return Holdout(float(per.sum()), per, int((mask > 0).sum()), info)


def searched_columns(ctx: Context, cand, fit: ModelFit) -> np.ndarray | None:
    """Block columns of the step times the held-out folds average over (every block
    boundary, the candidate's grid) when the added term is a step; None otherwise.

    Only a step's time is re-chosen by the folds. Its grid is every block boundary and,
    under flicker or walk noise, nearly every boundary is a separate test (the screening's
    effective number of tests m_eff is 370-500 on the measured-noise records), so the
    fold whose own excursion placed a step is credited with most of it. A searched scale
    (tau, r0, width) has m_eff 1.5-6: a smooth profile that the whole record sets. Averaging
    over a scale's grid too was tried on the measured-noise study (with the scale at ratio
    1.1 over the candidate's range) and refused a real lag (tau 1800 s, run 3) by 1.8
    nats where the fixed value kept it by 0.55 (benchmarks/RESULTS_loop_real.md)."""
    if cand.effect != Step.name or fit.terms[-1].kind != kinds.Step.name:
        return None
    return ctx.block_design(list(cand.grid))


class Comparison(NamedTuple):
    kept: bool
    lpd: float          # the model with the term, over the judging folds
    lpd_before: float   # the model without it, same folds
    folds: int          # folds that judge the term (module doc)
    se: float           # standard error of lpd - lpd_before (paired over folds)


def compare(with_term: Holdout, without: Holdout) -> Comparison:
    """Keep the term if the model with it predicts the folds that can judge it at least as
    well as the model without it (its new coefficients: the columns beyond ``without``'s)."""
    new = with_term.info[:, without.info.shape[1]:]
    judge = np.all(new >= MIN_INFORMATION, axis=1) if new.size else np.ones(
        with_term.per_fold.size, bool)
    d = with_term.per_fold[judge] - without.per_fold[judge]
    a = float(with_term.per_fold[judge].sum())
    b = float(without.per_fold[judge].sum())
    se = float(np.sqrt(d.size * np.var(d, ddof=1))) if d.size > 1 else 0.0
    return Comparison(bool(a >= b), a, b, int(judge.sum()), se)


def to_json(c: Comparison) -> dict:
    return {"folds_judging": c.folds, "folds": N_FOLDS, "lpd": c.lpd, "lpd_before": c.lpd_before,
            "diff_se": c.se, "kept": c.kept}
