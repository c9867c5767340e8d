"""Workflow for the ``composite`` model (paper 000): fit a rate-table run, compensate.

``fit_recording``: cells (:func:`fogbayes.composite.cells.rate_data`), the paper's sigma_d
table, orders given (``"s1,s2,u0,u1"``) or selected (``"loo"``, ``"waic"``, ``"sigma_d"``),
``method`` ``"joint"`` / ``"classification"`` / ``"product"``, optional NUTS (``bayes=True``),
and the compensator with a before/after table. :func:`compensate_recording` returns ``time``,
``rate`` (deg/s) and ``outlier`` (outside the invertible region), one row per row.
"""

from __future__ import annotations

import numpy as np

from ..data.documents import FIT_SCHEMA, validate_in_memory
from ..errors import FogbayesError, MissingColumnError, UnitError
from ..preprocess.operating_time import operating_time
from .cells import rate_data
from .classify import classify_fit
from .compensate import Compensator, build_compensator, compensate_draws
from .compare import select_orders
from .fit import fit_joint, fit_optax
from .model import (FullParams, Orders, OrdersError, Scaling, param_labels,
                    product_to_full, raw_map, raw_offset, read_orders, to_raw, unpack)
from .tables import before_after, format_table, nominal_rate

METHODS = ("joint", "classification", "product")
_SEGMENT_KEYS = ("rate_tolerance", "temperature_tolerance", "rate_threshold", "min_duration",
                 "trim_s", "stable_s", "smooth_s")


def _orders(orders) -> Orders | None:
    if orders is None or str(orders).strip().lower() == "auto":
        return None
    s1, s2, u0, u1 = read_orders(str(orders))  # three values: U1 has the order of U0
    if u1 is None:
        raise OrdersError(f"orders {orders!r}: fogbayes fit -m composite always fits paper "
                          f"000's drift U1(T) t", column="orders",
                          fix="give u1 (e.g. 0,0,2,0), or use fogbayes loop -m composite "
                              "for a model without the drift term")
    return Orders(s1, s2, u0, u1)


def _noise(noise) -> str:
    noise = "cells" if noise is None else str(noise).lower()
    return "ar1" if noise == "ar" else noise


def _interval(theta, cov, orders, sc, z=1.6448536269514722):
    J = raw_map(orders, sc)
    raw = J @ np.asarray(theta) + raw_offset(orders, sc)
    sd = np.sqrt(np.maximum(np.diag(J @ cov @ J.T), 0.0))
    return raw, sd, raw - z * sd, raw + z * sd


def _unflatten(vec, orders: Orders) -> dict:
    M = np.asarray(vec[:(orders.s1 + 1) * (orders.s2 + 1)]).reshape(orders.s1 + 1, orders.s2 + 1)
    nm = M.size
    return {"M": M.tolist(), "c": list(map(float, vec[nm:nm + orders.u0 + 1])),
            "d": list(map(float, vec[nm + orders.u0 + 1:]))}


def _fit(data, orders, method, noise):
    """(theta scaled, cov, sigma, noise document, extra document, scaling, converged)."""
    from .model import pack

    if method == "classification":
        from ..support.tails import norm_ppf, t_ppf

        cf = classify_fit(data, orders=orders)
        # d comes from a fit to n_T values U1(T_i): Student-t intervals on its dof
        dof_d = int(np.isfinite(cf.U1_levels).sum()) - orders.u1 - 1
        z = np.full(cf.cov.shape[0], norm_ppf(0.95))
        z[-(orders.u1 + 1):] = t_ppf(0.95, dof_d)
        return (np.asarray(pack(cf.params)), cf.cov, float("nan"),
                {"model": "cells (stage 2) / white (U1)", "z90": z.tolist()}, {}, cf.scaling,
                True)
    if method == "product":
        import jax
        import jax.numpy as jnp

        from .fit import _vector_to_theta

        pf = fit_optax(data, orders, form="product")
        full = product_to_full(pf.params)
        theta = np.asarray(pack(FullParams(*(jnp.asarray(v) for v in full))))
        # covariance of the full-matrix coefficients through the rank-1 map (delta method)
        v = jnp.concatenate(list(pf.params))
        Jm = np.asarray(jax.jacfwd(_vector_to_theta)(v, orders, "product"))
        return (theta, Jm @ pf.cov @ Jm.T, pf.sigma, {"model": "white"},
                {"product": {"a": np.asarray(pf.params.a).tolist(),
                             "b": np.asarray(pf.params.b).tolist(), "loss": pf.loss,
                             "grad_norm": pf.grad_norm}}, pf.scaling, pf.converged)
    if method != "joint":
        raise FogbayesError(f"unknown fit method {method!r}", column="method",
                            fix=f"use one of {', '.join(METHODS)}")
    ls = fit_joint(data, orders, noise=noise)
    doc = {"model": noise, "sigma": ls.sigma, "lam": ls.lam, "rho": ls.rho,
           "ar": ls.ar.tolist()}
    return np.asarray(pack(ls.params)), ls.cov, ls.sigma, doc, {}, ls.scaling, ls.converged


def fit_recording(rec, *, model: str = "composite", orders=None, bayes: bool = False,
                  seed: int = 0, method: str = "joint", noise: str | None = None,
                  order_criterion: str = "loo", operating_time: str = "cell",
                  T_nominal: float = 20.0, compensation: str = "halley",
                  schedule=None, num_warmup: int = 500, num_samples: int = 500,
                  num_chains: int = 4, **options) -> dict:
    """Fit the composite model to a rate-table Recording; returns the fit document."""
    import fogbayes

    if model != "composite":
        raise FogbayesError(f"this workflow fits 'composite', not {model!r}", column="model",
                            fix="use fogbayes.workflow.workflow_for(model)")
    unknown = set(options) - set(_SEGMENT_KEYS)
    if unknown:
        raise FogbayesError(f"unknown composite option(s) {sorted(unknown)}", column="--option",
                            fix=f"use method, noise, order_criterion, operating_time, T_nominal, "
                                f"compensation, schedule or {', '.join(_SEGMENT_KEYS)}")
    noise = _noise(noise)
    data, table = rate_data(rec, convention=operating_time, schedule=schedule, **options)
    paper = classify_fit(data)
    want = _orders(orders)
    selection = None
    if want is None:
        selection = select_orders(data, criterion=order_criterion, seed=seed)
        want = selection.orders
    theta, cov, sigma, noise_doc, extra, sc, ok = _fit(data, want, method, noise)
    raw, sd, lo, hi = _interval(theta, cov, want, sc,
                                np.asarray(noise_doc.get("z90", 1.6448536269514722)))
    doc = {
        "schema": FIT_SCHEMA, "model": "composite", "fogbayes_version": fogbayes.__version__,
        "method": method,
        "input": {"unit": rec.unit, "scale_factor": rec.scale_factor},
        "operating_time": operating_time, "T_nominal": float(T_nominal),
        "orders": {"s1": want.s1, "s2": want.s2, "u0": want.u0, "u1": want.u1,
                   "label": want.label()},
        "params": {"raw": _unflatten(raw, want), "labels": param_labels(want),
                   "raw_sd": _unflatten(sd, want), "raw_lo90": _unflatten(lo, want),
                   "raw_hi90": _unflatten(hi, want), "scaled": theta.tolist(),
                   "scaling": sc._asdict()},
        "noise": noise_doc, "cells": len(table.cells), "samples": int(data.U.size),
        "calibrated": {"temperature": [float(data.T.min()), float(data.T.max())],
                       "rate": [float(data.W.min()), float(data.W.max())]},
        "classification": {"orders": paper.orders.label(), "sigma_u1": paper.sigma_u1,
                           "sigma_s1": paper.sigma_s1, "sigma_s2": paper.sigma_s2},
        **extra,
    }
    if selection is not None:
        doc["order_selection"] = {"criterion": selection.criterion,
                                  "orders": selection.orders.label(),
                                  "scores": selection.scores}
    converged = bool(ok)
    if bayes:
        from .bayes import fit_bayes

        bf = fit_bayes(data, want, seed=seed, noise=noise, scaling=sc, warmup=num_warmup,
                       samples=num_samples, chains=num_chains)
        rd = bf.raw_draws().reshape(-1, theta.size)
        from ..inference.compare import information

        waic, loo = information(bf.idata, "waic"), information(bf.idata, "loo")
        th = bf.theta.reshape(-1, theta.size)
        step = max(1, th.shape[0] // 200)
        doc["bayes"] = {
            "noise": noise, "rhat_max": bf.rhat_max, "ess_min": bf.ess_min,
            "divergences": bf.divergences, "converged": bf.converged,
            "raw_mean": _unflatten(rd.mean(0), want),
            "raw_lo90": _unflatten(np.quantile(rd, 0.05, axis=0), want),
            "raw_hi90": _unflatten(np.quantile(rd, 0.95, axis=0), want),
            "elpd_waic": waic.elpd, "elpd_loo": loo.elpd,
            # ArviZ's reliability flags (Pareto k > 0.7; WAIC's posterior variance > 0.4)
            "loo_pareto_k_max": loo.pareto_k_max, "loo_warning": loo.warning,
            "waic_warning": waic.warning,
            "draws_scaled": th[::step].tolist(),
            "sigma_draws": (bf.sigma.reshape(-1)[::step] / sc.U_scale).tolist(),
        }
        converged = converged and bf.converged
    comp = compensator_from_fit(doc, method=compensation)
    W = np.asarray(comp(data.U, data.T, data.t).rate)
    rates = {"before": nominal_rate(to_raw(comp.params, comp.scaling), data.U, T_nominal=T_nominal),
             "fogbayes": W}
    if compensation != "paper":
        rates["paper"] = np.asarray(compensator_from_fit(doc, method="paper")(data.U, data.T, data.t).rate)
    cell_T = data.temperature_levels[data.cell_i]
    cell_W = data.rate_levels[data.cell_j]
    rows = before_after(cell_T, cell_W, data.cell, rates)
    doc["compensation"] = {"method": comp.method, "iterations": comp.iterations,
                           "box_scaled": list(comp.box),
                           "rate_range": [comp.box[0] * sc.W_scale, comp.box[1] * sc.W_scale]}
    doc["table"] = rows
    doc["table_markdown"] = format_table(rows, methods=tuple(rates))
    doc["residual_rate_rms"] = float(np.sqrt(np.mean((W - data.W) ** 2)))
    doc["converged"] = converged
    return doc


def _params_from_doc(fit: dict) -> tuple[FullParams, Scaling, Orders]:
    try:
        o = fit["orders"]
        orders = Orders(int(o["s1"]), int(o["s2"]), int(o["u0"]), int(o["u1"]))
        sc = Scaling(**{k: float(v) for k, v in fit["params"]["scaling"].items()})
        theta = np.asarray(fit["params"]["scaled"], float)
    except (KeyError, TypeError, ValueError) as exc:
        raise OrdersError(f"the composite fit document is incomplete ({exc!r})", column="params",
                          fix="pass the JSON written by 'fogbayes fit --model composite'") from None
    return unpack(theta, orders), sc, orders


def compensator_from_fit(fit: dict, *, method: str | None = None,
                         host: bool | None = None) -> Compensator:
    p, sc, _ = _params_from_doc(fit)
    cal = fit["calibrated"]
    comp = fit.get("compensation", {})
    method = method or comp.get("method", "halley")
    iters = comp.get("iterations") if method == comp.get("method") else None
    return build_compensator(p, sc, T_range=tuple(cal["temperature"]),
                             W_range=tuple(cal["rate"]), method=method, iterations=iters,
                             rtol=1e-9, host=host)


def _inputs(rec, fit: dict):
    src = rec.meta.source
    unit = (fit.get("input") or {}).get("unit")
    if unit is not None and rec.unit != unit:
        raise UnitError(f"the recording's output is in {rec.unit} but the fit was made in {unit}",
                        file=src, column="output", fix=f"load the recording with unit {unit}")
    if not rec.has_temperature:
        raise MissingColumnError("the composite model needs the temperature", file=src,
                                 column="temperature", fix="add a 'temperature' column in deg C")
    conv = fit.get("operating_time", "cell")
    if conv == "cell" and rec.input_rate is None:
        conv = "run"  # no rate steps to restart at: time since the record started
    t = operating_time(rec.time, rec.input_rate, None, convention=conv)
    return np.asarray(rec.output, float), np.asarray(rec.temperature, float), t


def compensate_recording(rec, fit: dict) -> dict[str, np.ndarray]:
    """Estimated input rate (deg/s) of every row; ``outlier`` where it is not invertible."""
    validate_in_memory(fit)
    U, T, t = _inputs(rec, fit)
    res = compensator_from_fit(fit)(U, T, t)
    return {"time": np.asarray(rec.time), "rate": np.asarray(res.rate),
            "outlier": ~np.asarray(res.in_range)}


def compensate_interval(rec, fit: dict, *, prob: float = 0.9, seed: int = 0) -> dict:
    """Posterior-predictive interval of the compensated rate (needs a ``bayes`` fit).

    Returns ``time``, ``rate`` (median), ``rate_lo``, ``rate_hi`` (central ``prob``).
    """
    import jax
    import jax.numpy as jnp

    if "bayes" not in fit:
        raise FogbayesError("the fit has no posterior draws", column="bayes",
                            fix="fit with bayes=True (fogbayes fit --bayes)")
    U, T, t = _inputs(rec, fit)
    comp = compensator_from_fit(fit)
    _, sc, orders = _params_from_doc(fit)
    draws = unpack(jnp.asarray(np.asarray(fit["bayes"]["draws_scaled"], float)), orders)
    med, lo, hi = compensate_draws(draws, sc, jnp.asarray(comp.box), U, T, t,
                                   key=jax.random.PRNGKey(seed),
                                   noise_sd=np.asarray(fit["bayes"]["sigma_draws"]), prob=prob,
                                   iterations=comp.iterations + 1)
    return {"time": np.asarray(rec.time), "rate": np.asarray(med), "rate_lo": np.asarray(lo),
            "rate_hi": np.asarray(hi)}
