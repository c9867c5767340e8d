"""Compensated output of the final loop model, one row per input row (``--compensated``).

bias-t / thermal / allan: output_comp = output - model error, in the input unit (the model
is fitted in deg/h and converted back). composite: the estimated input rate W (deg/s) that
solves U = f(W, T, t) for each sample, by Newton's method from the linear-scale guess
(5 fixed iterations, derivative by central differences; f is a low-order polynomial in W,
so this converges to machine precision on model-consistent data). Where f(W) does not
reproduce U at the solution (no inverse in reach, e.g. a measurement beyond the extremum of
a fitted nonlinearity) the rate is NaN and the row is flagged ``outlier``: never a silently
wrong rate.
"""

from __future__ import annotations

import numpy as np

from ..diagnose.context import Context
from ..diagnose.covariates import Covariates
from ..diagnose.fitting import ModelFit
from ..diagnose.terms import design
from ..units import convert_rate

_OMEGA_KINDS = ("omega_poly", "omega_abs", "omega_tpoly")
#: Largest |model(W) - U| / (1 + |U|) (deg/h) accepted at the solution; Newton on these
#: low-order polynomials reaches ~1e-12 in 5 steps where an inverse exists.
INVERSE_TOL = 1e-8


def _model(terms, beta, cov: Covariates) -> np.ndarray:
    return design(list(terms), cov) @ beta


def solve_rate(terms, beta, cov: Covariates, rate_deg_h: np.ndarray, *,
               iterations: int = 5) -> np.ndarray:
    """W (deg/s) with model(W) = measured rate (deg/h), per sample (Newton, module doc)."""
    scale = max(float(np.max(np.abs(cov.omega))), 1e-9) if cov.omega is not None else 1.0
    w0 = np.zeros_like(rate_deg_h)
    f0 = _model(terms, beta, cov._replace(omega=w0))
    h = 1e-4 * scale

    def slope_at(w):
        return (_model(terms, beta, cov._replace(omega=w + h))
                - _model(terms, beta, cov._replace(omega=w - h))) / (2 * h)

    slope = slope_at(w0)
    w = (rate_deg_h - f0) / slope
    for _ in range(iterations):
        f = _model(terms, beta, cov._replace(omega=w))
        d = slope_at(w)
        w = w - (f - rate_deg_h) / np.where(np.abs(d) > 0, d, slope)
    # no silent wrong rates: where the model does not reproduce the measurement at the
    # solution (no inverse, or Newton has not converged) the rate is NaN and the row flagged
    miss = np.abs(_model(terms, beta, cov._replace(omega=w)) - rate_deg_h)
    return np.where(miss <= INVERSE_TOL * (1.0 + np.abs(rate_deg_h)), w, np.nan)


def invert_rate(fit: ModelFit, cov: Covariates, rate_deg_h: np.ndarray, *,
                iterations: int = 5) -> np.ndarray:
    """:func:`solve_rate` with the terms and coefficients of ``fit``."""
    return solve_rate(fit.terms, fit.beta, cov, rate_deg_h, iterations=iterations)


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
