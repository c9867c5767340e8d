"""``bias-t`` / ``thermal`` fits of many same-shape recordings with one vmapped solve.

What is vectorised, and what is not (honestly): the workflow
(:func:`fogbayes.workflow.thermal.fit_recording`) is

1. covariates per sample and 1 s block means (NumPy, data-dependent gaps and masks),
2. order choice (only when several orders are asked for),
3. closed-form weighted least squares in the scaled basis,
4. 3-sigma (Pauta) flags on the per-sample residuals, iterated until none is new,
5. refit on the block means without the flagged samples, metrics per soak/ramp segment.

Steps 3 and 4's residual are one ``jax.jit(jax.vmap(...))`` call each over all sensors.
Steps 1, 5's block means and the metrics run once per *clock group* (recordings with identical
time stamps, as a rig's sensors have) on (sensors, samples) arrays (:mod:`.prepare`,
:mod:`.metrics`: one 2-D Savitzky-Golay call, block layouts built once, one reduction over
all sensors). What stays per recording: the Pauta iteration count, segment merging, and the
document itself. Order choice is not vectorised: ``orders`` must name one order. The solve,
per sensor ``s``::

    z'_s = (z_s - centre_s) / scale_s                (the sensor's own scaled basis)
    b_s  = argmin_b sum_i w_si (y_si - X(z'_si) b)^2  (w = samples per block)

Sensors with fewer blocks are padded with rows of weight 0 (they change no sum); the
residual variance uses each sensor's own ``m_s - p`` degrees of freedom, as the workflow
does. ``solver="gram"`` (default) uses the normal equations
(:func:`fogbayes.inference.lsq.lstsq_gram`, the batch path on CPU; same numbers as QR to
~1e-12 in a scaled basis; 1.4x faster than batched QR on CPU), ``"qr"`` the workflow's own
:func:`~fogbayes.inference.lsq.lstsq`. The documents equal the per-recording workflow's to
~1e-9 relative (tests/test_batch.py; measured 2e-14).

Speed (benchmarks/RESULTS_batch.md, 1 000 sensors x 3 600 samples, 2-core CPU, idle):
7.0x a loop of the per-recording workflow (1.25 s against 8.8 s), same coefficients to
2e-14. The batched solve alone is *not* faster than a Python loop over the same jitted
single-sensor solve on CPU (0.5-0.6x: memory-bound, and the loop's dispatch is cheap); it is
the program that would run as it is on a GPU.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import lru_cache, partial

import jax
import jax.numpy as jnp
import numpy as np

from ..errors import FogbayesError, TooShortError
from ..export import coefficient_document
from ..inference.compare import rms_criterion
from ..inference.lsq import lstsq, lstsq_gram
from ..metrics import DEFAULT_WINDOWS
from ..models.polynomial import PolyBasis, design
from ..models.thermal import thermal_basis
from ..preprocess import pauta_flags
from ..workflow._thermal_data import (
    Processing,
    fit_blocks,
    make_processing,
    sample_covariates,
)
from ..workflow.thermal import (
    MODELS,
    clamp_covariates,
    model_spec,
    parse_orders,
)
from . import prepare
from .files import FleetError
from .metrics import segment_reports

SOLVERS = {"gram": lstsq_gram, "qr": lstsq}
_UNSUPPORTED = ("order_criterion", "noise", "ar_order", "ma_order", "num_warmup",
                "num_samples", "num_chains", "level", "bayes_average_s")


def _unit_basis(basis: PolyBasis) -> PolyBasis:
    """The same monomials with centre 0 and scale 1: applied to already-scaled covariates."""
    c = len(basis.names)
    return PolyBasis(basis.names, basis.terms, (0.0,) * c, (1.0,) * c)


def _solve_one(z, y, w, centre, scale, n_valid, *, unit: PolyBasis, solver: str):
    """One sensor's weighted LSQ in its own scaled basis; dof from its own block count."""
    X = design((z - centre) / scale, unit)
    fit = SOLVERS[solver](X, y, w)
    dof = n_valid - unit.n_terms
    s2 = 2.0 * fit.loss / jnp.maximum(dof, 1.0)  # loss = wRSS / 2; padded rows add nothing
    cov = jnp.where(fit.sigma2 > 0, fit.covariance * (s2 / fit.sigma2), fit.covariance)
    return fit.params, cov, fit.residual, s2, dof, fit.converged & (dof > 0)


def _bias_one(coef, z, centre, scale, *, unit: PolyBasis):
    return design((z - centre) / scale, unit) @ coef


@lru_cache(maxsize=32)
def batched_solver(unit: PolyBasis, solver: str = "gram"):
    """``jit(vmap(solve))`` over sensors for one model structure (compiled once per shape)."""
    return jax.jit(jax.vmap(partial(_solve_one, unit=unit, solver=solver)))


@lru_cache(maxsize=32)
def batched_bias(unit: PolyBasis):
    return jax.jit(jax.vmap(partial(_bias_one, unit=unit)))


def _pad(rows: list[np.ndarray], m: int) -> np.ndarray:
    """Stack arrays of lengths <= m; padding repeats the last row (finite, weight 0)."""
    return np.stack([np.concatenate([r, np.repeat(r[-1:], m - len(r), axis=0)]) for r in rows])


def _prepare(rec, spec, proc, mask=None):
    """One recording's rate (deg/h), covariates, block means and scaled basis (the workflow's)."""
    rate = rec.rate("deg/h")
    z = sample_covariates(rec, spec, proc)
    return _reblock(rec, rate, z, spec, proc, mask)


def _prepare_all(recs, spec, proc, on_error) -> tuple[list[int], list[tuple]]:
    """(indices fitted, their (rate, z, blocks, basis)): per clock group in one go
    (:mod:`.prepare`); when that fails, recording by recording to report each bad one."""
    try:
        rates = [r.rate("deg/h") for r in recs]
        zs = prepare.covariates(recs, spec, proc)
        blocks = prepare.blocks(recs, rates, zs, spec, proc)
        return list(range(len(recs))), [_with_basis(r, y, z, b, spec) for r, y, z, b
                                         in zip(recs, rates, zs, blocks)]
    except FogbayesError:
        pass  # some recording cannot be fitted: find it (and any other) one by one
    keep, prep = [], []
    for i, rec in enumerate(recs):
        try:
            prep.append(_prepare(rec, spec, proc))
            keep.append(i)
        except FogbayesError as exc:
            if on_error is None:
                raise
            on_error(i, exc)
    return keep, prep


def _reblock(rec, rate, z, spec, proc, mask):
    return _with_basis(rec, rate, z, fit_blocks(rec, rate, z, spec, proc, mask), spec)


def _with_basis(rec, rate, z, blocks, spec):
    basis = thermal_basis(spec, blocks.z)
    if blocks.y.size < basis.n_terms + 2:  # the workflow's own limit (workflow.thermal._lsq)
        raise TooShortError(f"{blocks.y.size} block means cannot fit {basis.n_terms} "
                            "coefficients", file=rec.meta.source, column="output",
                            fix="record longer, average over shorter blocks or lower the order")
    return rate, z, blocks, basis


def _solve(blocks: list, bases: list, solver: str) -> list[tuple]:
    """One batched solve over sensors (blocks padded to one length); numpy results each."""
    m = max(b.y.size for b in blocks)
    w = _pad([b.count.astype(float) for b in blocks], m)
    for s, b in enumerate(blocks):
        w[s, b.y.size:] = 0.0
    args = (_pad([b.z for b in blocks], m), _pad([b.y for b in blocks], m), w,
            np.array([bs.centre for bs in bases]), np.array([bs.scale for bs in bases]),
            np.array([float(b.y.size) for b in blocks]))
    out = batched_solver(_unit_basis(bases[0]), solver)(*(jnp.asarray(a) for a in args))
    out = [np.asarray(a) for a in out]
    return [tuple(a[s] for a in out) for s in range(len(blocks))]


def _check(model: str, recs: list, orders, bayes: bool, options: dict) -> None:
    if model not in MODELS:
        raise FleetError(f"--vectorize fits bias-t or thermal, not '{model}'", column="--model",
                         fix="drop --vectorize for other models")
    if bayes or any(k in options for k in _UNSUPPORTED):
        raise FleetError("--vectorize fits the least-squares stage only (no posterior, one "
                         "order)", column="--vectorize", fix="drop --vectorize or --bayes")
    if len(parse_orders(model, orders)) != 1:
        raise FleetError(f"--vectorize needs one order, got '{orders}'", column="--orders",
                         fix="name one order (e.g. --orders 3), or drop --vectorize to choose")
    n, dt = recs[0].n, recs[0].sampling().dt_median
    for r in recs[1:]:
        if r.n != n or not np.isclose(r.sampling().dt_median, dt, rtol=1e-9):
            raise FleetError(f"{r.n} samples every {r.sampling().dt_median:g} s, the first "
                             f"recording has {n} every {dt:g} s", file=r.meta.source,
                             column="--vectorize",
                             fix="vectorise recordings of one length and sampling, or drop "
                                 "--vectorize")


def fit_vectorized(recs: list, *, model: str, orders: str | None = None, bayes: bool = False,
                   seed: int = 0, solver: str = "gram",
                   on_error: Callable[[int, FogbayesError], None] | None = None,
                   **options) -> list[dict | None]:
    """Fit documents of ``recs`` (same length and sampling), as ``fit_recording`` writes them.

    ``on_error(i, exc)``: a recording whose data cannot be fitted (no temperature column,
    too short, ...) is reported there and gets ``None`` instead of a document; without it
    the error is raised. ``seed`` is accepted for ``fit_recording``'s signature (nothing
    here is random).
    """
    import fogbayes

    if not recs:
        return []
    if solver not in SOLVERS:
        raise FogbayesError(f"unknown solver {solver!r}", column="solver", fix="use 'gram' or 'qr'")
    _check(model, recs, orders, bayes, options)
    known = set(Processing._fields[1:]) | {"processing", "windows", "cross", "extra", "gradient",
                                           "extra_order", "temperature"}
    bad = sorted(set(options) - known)
    if bad:
        raise FogbayesError(f"unknown option(s) {bad} for model {model}", column="options",
                            fix=f"use {', '.join(sorted(known))}")
    proc = make_processing(options.get("processing", "default"),
                           **{k: options[k] for k in Processing._fields[1:] if k in options})
    windows = tuple(options.get("windows", DEFAULT_WINDOWS))
    t_order, r_order = parse_orders(model, orders)[0]
    spec = model_spec(model, t_order, r_order, options)
    keep, prep = _prepare_all(recs, spec, proc, on_error)
    out: list[dict | None] = [None] * len(recs)
    if not keep:
        return out
    good = [recs[i] for i in keep]
    rates, zs, blocks, bases = (list(col) for col in zip(*prep))
    fits = _solve(blocks, bases, solver)
    flags = [None] * len(good)
    if proc.outliers == "pauta":
        bias = _bias(fits, zs, bases)
        flags = [pauta_flags(y - b, n_sigma=proc.n_sigma) for y, b in zip(rates, bias)]
        redo = [s for s, f in enumerate(flags) if f.count]
        if redo:  # refit the flagged sensors on block means without their flagged samples
            sub = [good[s] for s in redo]
            new = prepare.blocks(sub, [rates[s] for s in redo], [zs[s] for s in redo], spec,
                                 proc, [flags[s].mask for s in redo])
            for s, b in zip(redo, new):  # too few blocks left raises, as the workflow's refit
                _, _, blocks[s], bases[s] = _with_basis(good[s], rates[s], zs[s], b, spec)
            for s, fit in zip(redo, _solve([blocks[s] for s in redo], [bases[s] for s in redo],
                                           solver)):
                fits[s] = fit
    valid = [{nm: (float(a), float(b)) for nm, a, b in
              zip(bs.names, bl.z.min(axis=0), bl.z.max(axis=0))} for bs, bl in zip(bases, blocks)]
    # compensated output for the metrics, covariates clamped as compensation clamps them
    clamped = [clamp_covariates(z, bs, v) for z, bs, v in zip(zs, bases, valid)]
    rates_arr = np.stack(rates)
    after = rates_arr - _bias(fits, clamped, bases)
    metrics = segment_reports(rates_arr, after, [r.time for r in good],
                              prepare.segments(good, zs), windows=windows)
    for s, rec in enumerate(good):
        coef, cov, resid, s2, dof, ok = fits[s]
        out[keep[s]] = _document(rec, model, spec, proc, bases[s], blocks[s], valid[s], coef,
                                 cov, resid[:blocks[s].y.size], s2, dof, bool(ok), flags[s],
                                 metrics[s], fogbayes.__version__)
    return out


def _bias(fits, zs, bases) -> np.ndarray:
    """Modelled bias X(z_s) b_s at every sample of every sensor, one batched call."""
    return np.asarray(batched_bias(_unit_basis(bases[0]))(
        jnp.asarray(np.stack([f[0] for f in fits])), jnp.asarray(np.stack(zs)),
        jnp.asarray([b.centre for b in bases]), jnp.asarray([b.scale for b in bases])))


def _document(rec, model, spec, proc, basis, blocks, valid, coef, cov, resid, s2, dof, ok,
              flags, metrics, version) -> dict:
    """The fields of ``fit_recording``'s document (same keys, same order), from this solve."""
    warnings = [] if ok else [(
        "the design is rank deficient: some covariate does not vary enough (e.g. dT/dt in a "
        "record without ramps); coefficients are not identified")]
    return {
        "model": model, "fogbayes_version": version, "converged": ok, "warnings": warnings,
        "input": {"source": rec.meta.source, "sensor_id": rec.meta.sensor_id, "unit": rec.unit,
                  "scale_factor": rec.scale_factor, "n": rec.n},
        "params": {"spec": spec._asdict(), **coefficient_document(
            basis, coef, cov, units={"output": "deg/h", "T": "degC", "dT/dt": "degC/min"},
            valid_range=valid)},
        "processing": proc._asdict(),
        "outliers": {"method": proc.outliers, "n_sigma": proc.n_sigma,
                     "count": 0 if flags is None else flags.count},
        "fit": {"n_blocks": int(blocks.y.size), "n_params": basis.n_terms,
                "rms_criterion": rms_criterion(resid, basis.n_terms),
                "residual_std": float(np.sqrt(s2)), "dof": int(dof),
                "stderr_note": "least-squares standard errors assume white block means; "
                               "see 'bayes' for intervals with AR noise"},
        "metrics": metrics,
        "vectorized": True,
    }
