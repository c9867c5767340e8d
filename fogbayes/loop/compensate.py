"""Compensated output of the final loop model, one row per input row (``--compensated``).

bias-t / thermal / allan: output - model error, in the input unit. composite: per sample
U = a_0 + sum_m a_m^+- (W / W_s)^m solved for W by
:func:`fogbayes.composite.compensate.invert_polynomial` (Halley, monotone region), side of
W = 0 from sign((U - a_0) / a_1); out of reach: NaN and the row flagged ``outlier``.
"""

from __future__ import annotations

import numpy as np

from .context import Context
from ..preprocess.covariates import Covariates
from .fitting import ModelFit
from ..effects.kinds import kind_of
from ..effects.terms import columns, design
from ..errors import FogbayesError
from ..data.units import convert_rate


def _model(terms, beta, cov: Covariates) -> np.ndarray:
    return design(list(terms), cov) @ beta


def rate_polynomial(terms, beta, cov: Covariates, cols=None):
    """(a0, A_pos, A_neg, W_s): the model as a polynomial in w = W / W_s per sample.

    a0 (n,) is what does not depend on W; A_pos and A_neg (n, K) hold the coefficients of
    w^1 .. w^K for W >= 0 and W < 0. W_s is the first rate term's scale. ``cols``: the
    terms' columns on ``cov`` when already evaluated (a stream carries filter states).
    """
    n = cov.t.size
    parts, i = [], 0
    for tm in terms:
        k = tm.n_cols
        parts.append((tm, np.asarray(beta[i:i + k], float)))
        i += k
    rate_terms = [(tm, b) for tm, b in parts
                  if any(m for m, _ in kind_of(tm.kind).rate_powers(tm.params))]
    if not rate_terms:
        raise FogbayesError("the composite calibration has no term in the input rate W",
                            column="terms", fix="fit the composite model again (it needs a "
                                                "scale-factor term)")
    ws = float(rate_terms[0][0].params["scale"])
    top = max(m for tm, _ in rate_terms for m, _ in kind_of(tm.kind).rate_powers(tm.params))
    a0 = np.zeros(n)
    pos, neg = np.zeros((n, top)), np.zeros((n, top))
    for j, (tm, b) in enumerate(parts):
        powers = kind_of(tm.kind).rate_powers(tm.params)
        if not any(m for m, _ in powers):
            a0 += (columns(tm, cov) if cols is None else cols[j]) @ b
            continue
        s = float(tm.params["scale"])
        at_one = columns(tm, cov._replace(omega=np.full(n, s)))  # the factor at W = scale
        for j, (m, absolute) in enumerate(powers):
            c = b[j] * at_one[:, j] * (ws / s) ** m
            pos[:, m - 1] += c
            neg[:, m - 1] += (-1) ** m * c if absolute else c
    return a0, pos, neg, ws


def solve_rate(terms, beta, cov: Covariates, rate_deg_h: np.ndarray, cols=None) -> np.ndarray:
    """W (deg/s) with model(W) = measured rate (deg/h), per sample (module doc); ``cols``
    as :func:`rate_polynomial`."""
    from ..composite.compensate import invert_polynomial  # JAX: only a composite model's

    a0, pos, neg, ws = rate_polynomial(terms, beta, cov, cols)
    slope = 0.5 * (pos[:, 0] + neg[:, 0])  # dU/dw at 0, the |W| term left out
    # Scaled units per sample (w ~ 1 at full scale, the residual check in units of w): a
    # sample's solution then depends on that sample alone, as a stream's chunks need.
    u_s = np.maximum(np.abs(slope), 1e-300)
    y = (np.asarray(rate_deg_h, float) - a0) / u_s
    up = y * slope >= 0  # the side of W = 0 the solution lies on
    # one solve, each sample with its side's polynomial; no cap besides the folds (a
    # polynomial monotone on a side has one root there)
    w = invert_polynomial(np.where(up[:, None], pos, neg) / u_s[:, None], y, limit=np.inf)
    # the side must hold the solution (the other side's polynomial is not the model there)
    w = np.where((w >= 0) == up, w, np.where(np.abs(w) <= 1e-12, 0.0, np.nan))
    return w * ws


def invert_rate(fit: ModelFit, cov: Covariates, rate_deg_h: np.ndarray) -> np.ndarray:
    """:func:`solve_rate` with the terms and coefficients of ``fit``."""
    return solve_rate(fit.terms, fit.beta, cov, rate_deg_h)


def compensate(rec, ctx: Context, fit: ModelFit, model: str) -> dict[str, np.ndarray]:
    """The ``--compensated`` columns: time, output (or rate for composite), outlier."""
    cols = {"time": np.asarray(rec.time, float)}
    if model == "composite":
        cols["rate"] = invert_rate(fit, ctx.cov, ctx.rate)
        cols["outlier"] = ctx.outlier | ~np.isfinite(cols["rate"])
        return cols
    comp = ctx.rate - _model(fit.terms, fit.beta, ctx.cov)
    cols["output"] = convert_rate(comp, "deg/h", rec.unit, scale_factor=rec.scale_factor)
    cols["outlier"] = ctx.outlier.copy()
    return cols
