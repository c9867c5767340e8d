"""ARMA drift analysis of a recording (paper 002, section 2).

decimate -> detrend -> ACF/PACF -> fit candidates -> AIC/BIC -> whiteness -> prediction and
denoising -> optional posteriors. :func:`analyse_recording` returns the document and arrays,
:func:`fit_recording` the document; paper sign convention x_t = sum phi_i x_{t-i} + a_t - sum theta_j a_{t-j}.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..data import Recording
from ..data.documents import FIT_SCHEMA
from ..errors import ArgumentError, TimeOrderError
from .select import PAPER_CANDIDATES, grid_candidates, order_name, select_order
from .model import SIGN_CONVENTION
from .filter import Denoised, OneStep, denoise, one_step_prediction
from ..preprocess.detrend import detrend
from ..stats.acf import Correlogram, acf, pacf
from ..stats.whiteness import whiteness

#: fewest samples (after decimation) an ARMA analysis accepts
MIN_SAMPLES = 100
#: largest series for Bayesian WAIC/LOO (pointwise log-likelihood is draws x n floats)
MAX_BAYES_SAMPLES = 20_000


class ArmaAnalysis(NamedTuple):
    """The JSON document and the arrays behind it (time, detrended x, prediction, ...)."""

    document: dict
    time: np.ndarray
    x: np.ndarray
    trend: np.ndarray
    prediction: OneStep
    denoised: Denoised
    acf: Correlogram
    pacf: Correlogram


def parse_candidates(candidates: str) -> tuple[tuple[int, int], ...]:
    """'paper' | 'grid' | 'grid:P,Q' | explicit '1,0;2,1;...' -> tuple of (p, q)."""
    c = candidates.strip().lower()
    if c == "paper":
        return PAPER_CANDIDATES
    if c == "grid":
        return grid_candidates(3, 3)
    try:
        if c.startswith("grid:"):
            P, Q = (int(v) for v in c[5:].split(","))
            return grid_candidates(P, Q)
        out = tuple(tuple(int(v) for v in item.split(",")) for item in c.split(";") if item)
        if not out or any(len(o) != 2 or min(o) < 0 for o in out):
            raise ValueError
        return out  # type: ignore[return-value]
    except ValueError:
        raise ArgumentError(f"cannot read candidate orders {candidates!r}", argument="candidates",
                            fix="use 'paper', 'grid', 'grid:P,Q' or 'p,q;p,q;...' "
                                "(e.g. '1,0;2,1')") from None


def decimate_series(time: np.ndarray, x: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
    """Block means of k consecutive samples (an anti-alias average; a partial tail is dropped)."""
    m = (x.size // k) * k
    return time[:m].reshape(-1, k).mean(1), x[:m].reshape(-1, k).mean(1)


def _prepare(rec: Recording, decimate: int, detrend_order: int):
    if int(decimate) < 1:
        raise ArgumentError(f"decimate must be >= 1, got {decimate}", argument="decimate",
                            fix="give a positive integer factor, e.g. --decimate 10")
    if int(detrend_order) < 0:
        raise ArgumentError(f"detrend order must be >= 0, got {detrend_order}",
                            argument="detrend", fix="use 0 (mean only), 1 (linear), 2, ...")
    gaps = rec.sampling().gaps
    if gaps:
        g = gaps[0]
        raise TimeOrderError(f"ARMA models need uniform sampling; {len(gaps)} gap(s), the first "
                             f"of {g.duration:.6g} s before t = {g.start + g.duration:.6g} s",
                             file=rec.meta.source, column="time", row=g.index,
                             fix="analyse the gap-free pieces separately (Recording.slice)")
    rec.require(MIN_SAMPLES * int(decimate), "an ARMA analysis")
    t, y = decimate_series(rec.time, rec.output, int(decimate))
    d = detrend(y, t, order=int(detrend_order))
    return t, d.residual - d.residual.mean(), d.trend


def analyse_recording(rec: Recording, *, decimate: int = 1, detrend_order: int = 1,
                      candidates: str = "paper", criterion: str = "bic", lags: int | None = None,
                      bayes: bool = False, seed: int = 0, nlags: int = 40) -> ArmaAnalysis:
    """Run the whole ARMA analysis of ``rec`` (see module docstring) and build the document."""
    if criterion not in ("aic", "bic"):
        raise ArgumentError(f"criterion must be 'aic' or 'bic', got {criterion!r}",
                            argument="criterion", fix="use --criterion aic or --criterion bic")
    orders = parse_candidates(candidates)
    t, x, trend = _prepare(rec, decimate, detrend_order)
    sel = select_order(x, orders)
    best = int(sel.best(criterion))
    p, q = orders[best]
    phi, theta, s2 = sel.coefficients(best)
    f = sel.fits
    one = one_step_prediction(phi, theta, s2, x)
    white = whiteness(one.residual, x, p=p, q=q, lags=lags)
    den = denoise(phi, theta, s2, x)
    ac, pac = acf(x, nlags), pacf(x, nlags)
    doc = {
        "schema": FIT_SCHEMA, "model": "arma", "sign_convention": SIGN_CONVENTION,
        "statsmodels_equivalent": "ARIMA(order=(p, 0, q), trend='n'): ar = phi, ma = -theta",
        "unit": rec.unit, "n": int(x.size), "decimate": int(decimate),
        "sample_rate_hz": float(rec.sample_rate / int(decimate)), "detrend_order": int(detrend_order),
        "criterion": criterion, "selected": order_name(p, q),
        "selected_aic": order_name(*sel.selected("aic")),
        "selected_bic": order_name(*sel.selected("bic")),
        "candidates": [
            {"p": a, "q": b, "name": order_name(a, b), "aic": float(sel.aic[i]),
             "bic": float(sel.bic[i]), "loglik": float(f.loglik[i]),
             "converged": bool(f.converged[i]), "phi": np.asarray(f.phi[i, :a]),
             "theta": np.asarray(f.theta[i, :b]), "sigma2": float(f.sigma2[i])}
            for i, (a, b) in enumerate(orders)],
        "params": {"p": p, "q": q, "phi": phi, "theta": theta, "sigma2": s2,
                   "se_phi": np.asarray(f.se_phi[best, :p]),
                   "se_theta": np.asarray(f.se_theta[best, :q]),
                   "se_sigma2": float(f.se_sigma2[best])},
        "converged": bool(f.converged[best]),
        "whiteness": white._asdict(),
        "residual": {"mean": float(one.residual.mean()), "variance": float(one.residual.var())},
        "denoise": {"noise_var": den.noise_var, "removed_noise_std": float(den.noise.std()),
                    "signal_std": float(den.smoothed.std()),
                    "method": "canonical signal + white noise; Kalman filter and RTS smoother"},
        "acf": {"lags": ac.lags, "values": ac.values, "band": ac.band, "alpha": ac.alpha},
        "pacf": {"lags": pac.lags, "values": pac.values, "band": pac.band, "alpha": pac.alpha},
    }
    if bayes:
        doc["bayes"] = _bayes_section(x, orders, seed)
    from .. import __version__

    doc["fogbayes_version"] = __version__
    return ArmaAnalysis(doc, t, x, trend, one, den, ac, pac)


def _bayes_section(x: np.ndarray, orders, seed: int) -> dict:
    if x.size > MAX_BAYES_SAMPLES:
        raise ArgumentError(f"Bayesian WAIC/LOO keeps draws x n pointwise log-likelihoods; "
                            f"n = {x.size} exceeds {MAX_BAYES_SAMPLES}", argument="bayes",
                            fix="decimate further (--decimate) or analyse a slice")
    from .bayes import compare_orders_bayes

    c = compare_orders_bayes(x, orders, seed=seed)
    return {"waic_loo": [
        {"p": a, "q": b, "name": order_name(a, b), "elpd_waic": float(c.elpd_waic[i]),
         "se_waic": float(c.se_waic[i]), "elpd_loo": float(c.elpd_loo[i]),
         "se_loo": float(c.se_loo[i]), "pareto_k_max": float(c.pareto_k_max[i]),
         "waic_warning": bool(c.waic_warning[i]),
         "phi_mean": c.posteriors[i].phi, "theta_mean": c.posteriors[i].theta,
         "sigma2_mean": c.posteriors[i].sigma2, "converged": c.posteriors[i].converged,
         "rhat_max": c.posteriors[i].rhat_max, "ess_bulk_min": c.posteriors[i].ess_bulk_min,
         "divergences": c.posteriors[i].divergences}
        for i, (a, b) in enumerate(orders)],
        "selected_waic": order_name(*orders[int(np.argmax(c.elpd_waic))]),
        "selected_loo": order_name(*orders[int(np.argmax(c.elpd_loo))])}


def fit_recording(rec: Recording, *, model: str = "arma", orders: str | None = None,
                  bayes: bool = False, seed: int = 0, **options) -> dict:
    """Workflow-contract entry point: the ARMA document of :func:`analyse_recording`."""
    if model != "arma":
        raise ArgumentError(f"the ARMA workflow fits model 'arma', not {model!r}", argument="model",
                            fix="use fogbayes.workflow.workflow_for(model) for other models")
    return analyse_recording(rec, candidates=orders or "paper", bayes=bayes, seed=seed,
                             **options).document
