"""Pooled thermal bias laws of several units of one sensor type: population, spread, outliers.

Per unit b(T) = sum_k a_k (T - T_ref)^k as the closed loop publishes it
(:func:`fogbayes.loop.estimator.publish`: GLS under the noise model less its random walk, the
IEEE 952 constant, the covariance under the full noise at its REML hyperparameters), rebased
to powers of T - T_ref
(:func:`fogbayes.models.polynomial.rebase_matrix`): y_u = a_u, Sigma_u = M_u C_u M_u'. Population:
:mod:`fogbayes.pool.normal` on (y - median) / k per coefficient. Reports (90 %) population mean,
between-unit sd, a new unit's range, each unit alone and pooled, outlier p-values; the spread
is diagonal about ``T_ref`` (default 20 deg C).
"""

from __future__ import annotations

from typing import NamedTuple, Sequence

import numpy as np

from ..errors import FogbayesError
from ..allan.fit import Z90

CI = 0.9
FLAG_LEVEL = 0.01
T_REF = 20.0


def names(order: int) -> list[str]:
    """Coefficient names: a0 (bias at T_ref), a1 (per deg C), a2 (per deg C^2), ..."""
    return [f"a{k}" for k in range(order + 1)]


def units_of(order: int) -> list[str]:
    return ["deg/h"] + [f"deg/h/degC^{k}" if k > 1 else "deg/h/degC" for k in range(1, order + 1)]


class ThermalUnit(NamedTuple):
    """One unit's bias law in the common basis (powers of T - t_ref), deg/h."""

    name: str
    source: str | None
    n: int
    coef: np.ndarray       # (order + 1,)
    cov: np.ndarray        # (order + 1, order + 1)
    t_range: tuple[float, float]
    converged: bool


def fit_unit(rec, *, order: int = 2, t_ref: float = T_REF, name: str | None = None) -> ThermalUnit:
    """The published bias law of one recording, mapped to powers of ``T - t_ref`` (module doc)."""
    from ..loop.context import make_context
    from ..loop.fitting import fit_terms
    from ..loop.bases import base_terms
    from ..loop.estimator import publish, reml_noise
    from ..models.polynomial import PolyBasis, rebase_matrix

    ctx = make_context(rec)
    terms = base_terms(ctx, "bias-t", str(order), source=rec.meta.source)
    if len(terms) < 2:
        raise FogbayesError("the temperature does not vary (a soak): no bias law in T to "
                            "pool", file=rec.meta.source, column="temperature",
                            fix="pool recordings of a temperature sweep, or leave this one out")
    fit = fit_terms(ctx, terms)
    # as the loop publishes: the walk does not pull the law, the covariance under REML noise
    # (ML leaves too little of the slow noise the constant and slope share; the coverage of
    # both: benchmarks/RESULTS_loop.md)
    pub = publish(ctx, fit, cov_noise=reml_noise(ctx, fit)).noise
    beta, cov = np.asarray(pub.beta, float), np.asarray(pub.cov_beta, float)
    p = terms[1].params
    basis = PolyBasis(("T",), tuple((k,) for k in range(order + 1)), (float(p["centre"]),),
                      (float(p["scale"]),))
    M = rebase_matrix(basis, origin=[t_ref], unit=[1.0])
    T = np.asarray(ctx.cov.T[:, 0], float)
    return ThermalUnit(name or rec.meta.sensor_id, rec.meta.source, int(rec.n), M @ beta,
                       M @ cov @ M.T, (float(T.min()), float(T.max())),
                       bool(fit.noise.converged))


def _interval(draws: np.ndarray, unit: str) -> dict:
    lo, med, hi = np.quantile(draws, [0.5 - CI / 2, 0.5, 0.5 + CI / 2])
    return {"value": float(med), "low": float(lo), "high": float(hi), "unit": unit}


def pool_thermal(units: Sequence[ThermalUnit], *, t_ref: float = T_REF, seed: int = 0,
                 flag_level: float = FLAG_LEVEL, **sampler) -> dict:
    """Pool the units' bias laws; a JSON-able document (module docstring)."""
    from .normal import fit_pool

    order = int(units[0].coef.size) - 1
    if any(u.coef.size != order + 1 for u in units):
        raise FogbayesError("the units' bias laws have different orders", column="--order",
                            fix="fit every unit with the same --order")
    y = np.stack([u.coef for u in units])
    cov = np.stack([u.cov for u in units])
    se = np.sqrt(np.diagonal(cov, axis1=1, axis2=2))
    m = np.median(y, axis=0)
    k = np.maximum(1.4826 * np.median(np.abs(y - m), axis=0), np.median(se, axis=0))
    k = np.where(k > 0, k, 1.0)
    res = fit_pool((y - m) / k, cov / np.outer(k, k), names(order), seed=seed,
                   flag_level=flag_level, **sampler)
    mu, spread = m + k * res.mu, k * res.spread
    pooled, new = m + k * res.units, m + k * res.new_unit
    labels, unit_names = names(order), units_of(order)
    population = {}
    for j, (t, un) in enumerate(zip(labels, unit_names)):
        lo, hi = np.quantile(new[:, j], [0.5 - CI / 2, 0.5 + CI / 2])
        population[t] = {"mean": _interval(mu[:, j], un), "spread_sd": _interval(spread[:, j], un),
                         "new_unit": {"low": float(lo), "high": float(hi), "unit": un}}
    rows = []
    for i, u in enumerate(units):
        per = {t: {"single": {"value": float(u.coef[j]), "low": float(u.coef[j] - Z90 * se[i, j]),
                              "high": float(u.coef[j] + Z90 * se[i, j]), "unit": unit_names[j]},
                   "pooled": _interval(pooled[:, i, j], unit_names[j])}
               for j, t in enumerate(labels)}
        p = float(res.outlier_p[i])
        rows.append({"name": u.name, "source": u.source, "n": u.n,
                     "temperature_range": list(u.t_range), "converged": u.converged,
                     "terms": per, "outlier": {"p": p, "flagged": bool(p < flag_level),
                                               "method": res.diagnostics["loo_method"][i]}})
    diag = {k_: v for k_, v in res.diagnostics.items() if k_ != "loo_method"}
    lo_all = max(u.t_range[0] for u in units)
    hi_all = min(u.t_range[1] for u in units)
    warnings = []
    if not lo_all <= t_ref <= hi_all:
        warnings.append(f"T_ref {t_ref:g} deg C lies outside the temperature range all units "
                        f"share ([{lo_all:.3g}, {hi_all:.3g}]): a0 is extrapolated there")
    failed = [u.name for u in units if not u.converged]
    if failed:
        warnings.append(f"the noise fit did not converge for {', '.join(failed)}")
    return {"terms": labels, "t_ref": t_ref, "ci": CI, "flag_level": flag_level,
            "law": "b(T) = sum_k a_k (T - t_ref)^k, deg/h",
            "population": population, "units": rows,
            "flagged": [r["name"] for r in rows if r["outlier"]["flagged"]],
            "warnings": warnings, "diagnostics": diag, "converged": bool(diag["converged"]),
            "method": "hierarchical normal model (fogbayes.pool.normal) of each unit's GLS bias "
                      "law under its fitted noise model, in powers of T - t_ref, standardised "
                      "per coefficient; NUTS on the population mean and spread"}
