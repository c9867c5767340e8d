"""``bias-t`` / ``thermal`` fits of many same-shape recordings in one batched pass.

The steps of :func:`fogbayes.thermal.workflow.fit_recording` (covariates and block means,
least squares in the scaled basis, Pauta flags iterated, refit, segment metrics) once for all
sensors: per clock group :mod:`.prepare` and :mod:`.metrics`; the solve by :mod:`.kernels`
(``solver="numba"``) or :mod:`.xla` (``"gram"``, ``"qr"``). b_s = argmin sum_i w_si
(y_si - X(z'_si) b)^2, w = samples per block (0 for empty or padding), s^2 on m_s - p
degrees of freedom. ``orders`` must name one order.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import lru_cache
from typing import NamedTuple

import jax
import numpy as np

from ..errors import FogbayesError, TooShortError
from ..stats.stability import DEFAULT_WINDOWS
from ..models.polynomial import PolyBasis, range_scaling
from ..thermal.model import covariate_names, thermal_terms
from ..thermal.data import fit_blocks, processing_of_options, sample_covariates
from ..thermal.workflow import (
    MODELS,
    model_spec,
    parse_orders,
)
from . import kernels, prepare, xla
from .documents import fit_documents
from .files import FleetError
from .metrics import segment_reports
from .runtime import cyclic_gc_paused, one_blas_thread

RCOND = 1e-10  # rank test of the solvers (inference.lsq's default)
_UNSUPPORTED = ("order_criterion", "noise", "ar_order", "ma_order", "num_warmup",
                "num_samples", "num_chains", "level", "bayes_average_s")


def default_solver() -> str:
    """Compiled loops over sensors on a CPU; the jit(vmap) normal equations on a GPU/TPU."""
    return "numba" if jax.default_backend() == "cpu" else "gram"


def _prepare(rec, spec, proc) -> tuple:
    """One recording's rate (deg/h), covariates and block means (the workflow's)."""
    rate = rec.rate("deg/h")
    z = sample_covariates(rec, spec, proc)
    blocks = fit_blocks(rec, rate, z, spec, proc, None)
    _check_blocks(rec, blocks.y.size, spec)
    return rate, z, blocks


def _prepare_all(recs, spec, proc, on_error, groups) -> tuple[list[int], np.ndarray, np.ndarray,
                                                       prepare.BlockArrays]:
    """Indices fitted, their rates (S, n), covariates (S, c, n) and block arrays: per clock
    group in one go (:mod:`.prepare`); when that fails, recording by recording to report
    each bad one."""
    try:
        R = np.stack([r.rate("deg/h") for r in recs])
        Z = prepare.covariates(recs, spec, proc, groups)
        arrays = prepare.block_arrays(recs, R, Z, spec, proc, groups=groups)
        for r, k in zip(recs, (arrays.count > 0).sum(axis=1).tolist()):
            _check_blocks(r, k, spec)
        return list(range(len(recs))), R, Z, arrays
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
    if not keep:
        return [], np.empty((0, 0)), np.empty((0, 0, 0)), None
    rates, zs, blocks = zip(*prep)
    return keep, np.stack(rates), prepare.covariate_major(zs), prepare.stack_blocks(blocks)


def _check_blocks(rec, n_blocks: int, spec) -> None:
    p = _n_terms(spec)
    if n_blocks < p + 2:  # the workflow's own limit (thermal.workflow._lsq)
        raise TooShortError(f"{n_blocks} block means cannot fit {p} coefficients",
                            file=rec.meta.source, column="output",
                            fix="record longer, average over shorter blocks or lower the order")


@lru_cache(maxsize=32)
def _n_terms(spec) -> int:
    return len(thermal_terms(spec))


class Fits(NamedTuple):
    """Least-squares results of every sensor, stacked: coef (S, p), cov (S, p, p), rss (S,)
    (unweighted residual sum of squares over its blocks: the RMS criterion's), s2, dof, ok."""

    coef: np.ndarray
    cov: np.ndarray
    rss: np.ndarray
    s2: np.ndarray
    dof: np.ndarray
    ok: np.ndarray


def _fit(arrays: prepare.BlockArrays, spec, solver: str
         ) -> tuple[list[PolyBasis], np.ndarray, np.ndarray, Fits]:
    """Every sensor's scaled basis (its blocks' covariate range), that range lo/hi (S, c)
    and the batched least-squares solve in those bases, each block weighted by its count
    (count-0 blocks weigh nothing)."""
    w = arrays.count.astype(float)
    n_valid = (arrays.count > 0).sum(axis=1).astype(float)
    lo, hi = kernels.covariate_range(arrays.z, w)
    centre, scale = range_scaling(lo, hi)
    names, terms = covariate_names(spec), thermal_terms(spec)
    bases = [PolyBasis(names, terms, tuple(c), tuple(s))
             for c, s in zip(centre.tolist(), scale.tolist())]
    if solver == "numba":
        fits = Fits(*kernels.fit_gram(arrays.z, arrays.y, w, centre, scale, n_valid,
                                      _exponents(bases[0]), RCOND))
    else:
        fits = Fits(*xla.fit(arrays.z, arrays.y, w, centre, scale, n_valid, bases[0], solver))
    return bases, lo, hi, fits


def _replace(fits: Fits, rows: np.ndarray, new: Fits) -> Fits:
    """``fits`` with the sensors ``rows`` taken from ``new``."""
    out = [np.array(old) for old in fits]
    for o, upd in zip(out, new):
        o[rows] = upd
    return Fits(*out)


def _check(model: str, recs: list, groups: list, orders, bayes: bool, options: dict) -> None:
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
    for group in groups[1:]:  # a rig's sensors share one clock
        r = recs[group[0]]
        if r.n != n or not np.isclose(r.sampling().dt_median, dt, rtol=1e-9):
            raise FleetError(f"{r.n} samples every {r.sampling().dt_median:g} s, the first "
                             f"recording has {n} every {dt:g} s", file=r.meta.source,
                             column="--vectorize",
                             fix="vectorise recordings of one length and sampling, or drop "
                                 "--vectorize")


def fit_vectorized(recs: list, *, model: str, orders: str | None = None, bayes: bool = False,
                   seed: int = 0, solver: str | None = None,
                   on_error: Callable[[int, FogbayesError], None] | None = None,
                   **options) -> list[dict | None]:
    """Fit documents of ``recs`` (same length and sampling), as ``fit_recording`` writes them.

    ``on_error(i, exc)``: a recording whose data cannot be fitted (no temperature column,
    too short, ...) is reported there and gets ``None`` instead of a document; without it
    the error is raised. ``seed`` is accepted for ``fit_recording``'s signature (nothing
    here is random).
    """
    # ~10^5 small acyclic objects (segments, layouts, documents); spinning BLAS threads
    # would take the cores from the compiled loops
    with cyclic_gc_paused(), one_blas_thread():
        return _fit_documents(recs, model, orders, bayes, solver, on_error, options)


def _fit_documents(recs, model, orders, bayes, solver, on_error, options) -> list[dict | None]:
    import fogbayes

    if not recs:
        return []
    solver = default_solver() if solver is None else solver
    if solver not in ("numba", *xla.SOLVERS):
        raise FogbayesError(f"unknown solver {solver!r}", column="solver",
                            fix="use 'numba' (CPU), 'gram' or 'qr' (jit(vmap), any device)")
    groups = prepare.clock_groups(recs)  # a rig's sensors share one clock: work per group
    _check(model, recs, groups, orders, bayes, options)
    proc = processing_of_options(model, options, {"windows", "cross", "extra", "gradient",
                                                  "extra_order", "temperature"})
    windows = tuple(options.get("windows", DEFAULT_WINDOWS))
    t_order, r_order = parse_orders(model, orders)[0]
    spec = model_spec(model, t_order, r_order, options)
    keep, R, Z, arrays = _prepare_all(recs, spec, proc, on_error, groups)
    out: list[dict | None] = [None] * len(recs)
    if not keep:
        return out
    if len(keep) < len(recs):
        groups = None  # some recordings failed: regroup those left
    good = [recs[i] for i in keep]
    bases, lo, hi, fits = _fit(arrays, spec, solver)
    block_count = arrays.count
    count = None  # Pauta-flagged samples per sensor
    if proc.outliers == "pauta":
        mask, count = _flags(solver, R, fits.coef, Z, bases, proc.n_sigma)
        redo = np.flatnonzero(count)
        if redo.size:  # refit the flagged sensors on block means without their flagged samples
            every = redo.size == len(good)  # (as in a chamber test: every sensor has a few)
            new = prepare.block_arrays(good, R, Z, spec, proc, ~mask, groups=groups) if every \
                else prepare.block_arrays([good[s] for s in redo], R[redo], Z[redo], spec, proc,
                                          ~mask[redo])
            for s, k in zip(redo, (new.count > 0).sum(axis=1).tolist()):
                _check_blocks(good[s], k, spec)  # too few blocks left raises, as the workflow's
            new_bases, lo[redo], hi[redo], new_fits = _fit(new, spec, solver)
            for s, bs in zip(redo, new_bases):
                bases[s] = bs
            fits = new_fits if every else _replace(fits, redo, new_fits)
            block_count = new.count if every else _replace_counts(block_count, redo, new.count)
    # compensated output for the metrics, covariates clamped as compensation clamps them
    after = R - _bias(solver, fits.coef, Z, bases, lo, hi)
    metrics = segment_reports(R, after, [r.time for r in good],
                              prepare.segments(good, Z[:, 0, :], groups), windows=windows)
    docs = fit_documents(good, model, spec, proc, bases, fits, lo, hi,
                         (block_count > 0).sum(axis=1), count, metrics, fogbayes.__version__)
    for k, doc in zip(keep, docs):
        out[k] = doc
    return out


def _replace_counts(count: np.ndarray, rows: np.ndarray, new: np.ndarray) -> np.ndarray:
    m = max(count.shape[1], new.shape[1])
    out = np.zeros((count.shape[0], m), np.int64)
    out[:, :count.shape[1]] = count
    out[rows] = 0
    out[rows, :new.shape[1]] = new
    return out


def _bias(solver: str, coef: np.ndarray, Z: np.ndarray, bases: list, lo=None, hi=None
          ) -> np.ndarray:
    """Modelled bias X(z_si) b_s at every sample of every sensor (Z (S, c, n)), one call;
    with ``lo``/``hi`` (S, c) the covariates are clamped to that range first."""
    centre = np.array([b.centre for b in bases])
    scale = np.array([b.scale for b in bases])
    if solver == "numba":
        inf = np.full(centre.shape, np.inf)
        return kernels.evaluate(coef, Z, centre, scale, _exponents(bases[0]),
                                -inf if lo is None else lo, inf if hi is None else hi)
    return xla.bias(coef, Z, centre, scale, bases[0], lo, hi)


def _flags(solver: str, R: np.ndarray, coef: np.ndarray, Z: np.ndarray, bases: list,
           n_sigma: float) -> tuple[np.ndarray, np.ndarray]:
    """Pauta flags (``pauta_flags``, its 100 passes at most) of every sensor's residual
    ``R - X(z) b`` at every sample: mask (S, n), count (S,)."""
    if solver == "numba":
        centre = np.array([b.centre for b in bases])
        scale = np.array([b.scale for b in bases])
        return kernels.residual_pauta(R, coef, Z, centre, scale, _exponents(bases[0]),
                                      n_sigma, 100)
    mask, count, _, _ = kernels.pauta(R - _bias(solver, coef, Z, bases), n_sigma, 100)
    return mask, count


def _exponents(basis: PolyBasis) -> np.ndarray:
    return np.array(basis.terms, np.int64).reshape(basis.n_terms, len(basis.names))
