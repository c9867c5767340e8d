"""``fogbayes fit --estimator gls``: the closed loop's fit with no step added.

GLS under the loop's noise model less its random walk, the IEEE 952 constant, the covariance
under the full model (:mod:`fogbayes.loop.estimator`). Same path, default orders
(:data:`fogbayes.thermal.workflow.DEFAULT_ORDERS`) and document (``fogbayes.loop/1``) as
``fogbayes loop --max-steps 0``.
"""

from __future__ import annotations

import re

from ..errors import ArgumentError
from ..thermal.workflow import DEFAULT_ORDERS

MODELS = ("bias-t", "thermal")
#: as ``fogbayes loop``: fewer samples leave the noise model without data
MIN_SAMPLES = 100


def gls_orders(model: str, orders: str | None) -> str:
    """``fogbayes fit``'s orders for the GLS path: fixed orders only (no range, no auto)."""
    if model not in MODELS:
        raise ArgumentError(f"--estimator gls fits models {', '.join(MODELS)}, not '{model}'",
                            column="--estimator",
                            fix=f"use --estimator ols for {model}, or -m bias-t / -m thermal")
    text = DEFAULT_ORDERS[model] if orders in (None, "") else str(orders).strip()
    if not re.fullmatch(r"\d+(,\d+)?", text.replace(" ", "")):
        raise ArgumentError(f"--estimator gls takes fixed orders, got '{orders}'",
                            column="--orders",
                            fix="give the orders, e.g. --orders 3 (bias-t) or 2,1 (thermal); "
                                "choose them first with --estimator ols --orders auto")
    return text.replace(" ", "")


def fit_gls(rec, model: str, orders: str | None = None, *, seed: int = 0) -> dict:
    """The loop document of ``run_loop(rec, model, orders, max_steps=0)`` (module doc)."""
    from ..errors import TooShortError
    from .core import run_loop

    if rec.n < MIN_SAMPLES:
        raise TooShortError(f"--estimator gls needs at least {MIN_SAMPLES} samples (its noise "
                            f"model is fitted on block means), the recording has {rec.n}",
                            file=rec.meta.source, fix="use --estimator ols on short records")

    return run_loop(rec, model, orders=gls_orders(model, orders), max_steps=0,
                    seed=seed).to_json()


def summary_line(doc: dict) -> str:
    """One line for people: the estimator, its noise model and the residual 10 s RMS."""
    noise = doc.get("calibration", {}).get("noise", {})
    parts = ["white"] + (["flicker"] if noise.get("flicker_bank") else [])
    k = int(noise.get("gauss_markov_components") or 0)
    parts += [f"{k} Gauss-Markov"] if k else []
    walk = " (covariance with the random walk)" if noise.get("random_walk") else ""
    return (f"{doc.get('model')}: GLS under {' + '.join(parts)} noise{walk}, "
            f"converged={noise.get('converged')}; residual 10 s RMS "
            f"{doc['final']['rms']:.4g} deg/h")
