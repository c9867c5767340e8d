"""Workflow for the ``bias-t`` and ``thermal`` models: fit a Recording, compensate one.

``fit_recording``: covariates, 1 s block means (:mod:`.data`), orders (RMS criterion or
PSIS-LOO/WAIC, ``order_criterion``), least squares (:func:`fogbayes.inference.lsq.lstsq`), Pauta
flags and refit, optional NUTS (``bayes=True``), B0 and Bs before/after. ``orders``: bias-t
``"3"``, ``"1-4"``, ``"auto"``; thermal ``"2"``, ``"2,1"``, ``"1-3,1-2"``, ``"auto"``
(:data:`DEFAULT_ORDERS`). Compensation (:mod:`fogbayes.thermal.compensate`) clamps covariates to
the fitted range and flags 3-sigma outliers.
"""

from __future__ import annotations

import re

import numpy as np

from ..data.documents import FIT_SCHEMA, validate_in_memory
from ..errors import FogbayesError, NonFiniteError, TooShortError
from ..models.basis_document import basis_from_dict, coefficient_document
from ..inference.compare import rms_criterion, select_order
from ..inference.lsq import conditioning, identifiability, lstsq
from ..stats.stability import DEFAULT_WINDOWS, segment_report
from ..models.polynomial import design
from .model import OrderError, ThermalSpec, check_spec, thermal_basis
from ..preprocess import pauta_flags, segment_thermal
from ..preprocess.outliers import gross_error_flags
from ..data.units import convert_rate
from .data import Processing, fit_blocks, processing_of_options, sample_covariates

MODELS = ("bias-t", "thermal")
DEFAULT_ORDERS = {"bias-t": "3", "thermal": "2"}
_AUTO = {"bias-t": "1-4", "thermal": "1-3,1-2"}
_SPEC_KEYS = ("cross", "extra", "gradient", "extra_order", "temperature")
_BAYES_KEYS = ("noise", "ar_order", "ma_order", "num_warmup", "num_samples", "num_chains",
               "level", "bayes_average_s")
_OTHER_KEYS = ("processing", "windows", "order_criterion")
#: |rate| above this (deg/h; ~770 revolutions/s) is no gyro reading: a gross error.
RATE_LIMIT_DEG_H = 1e9


def _range(text: str, model: str) -> list[int]:
    m = re.fullmatch(r"\s*(\d+)\s*(?:-\s*(\d+)\s*)?", text)
    if not m or (m.group(2) and int(m.group(2)) < int(m.group(1))):
        raise OrderError(f"cannot read order '{text}' for model {model}", column="orders",
                         fix="use e.g. '3', '1-4' or 'auto' (thermal: '2,2' or '1-3,1-2')")
    lo = int(m.group(1))
    return list(range(lo, int(m.group(2) or lo) + 1))


def parse_orders(model: str, orders: str | None) -> list[tuple[int, int]]:
    """Candidate (T order, dT/dt order) pairs for ``model`` (see the module doc)."""
    text = DEFAULT_ORDERS[model] if orders in (None, "") else str(orders).strip().lower()
    text = _AUTO[model] if text == "auto" else text
    parts = text.split(",")
    if model == "bias-t":
        if len(parts) != 1:
            raise OrderError(f"bias-t has one order (T), got '{orders}'", column="orders",
                             fix="use e.g. --order 3, or --model thermal for a dT/dt order")
        return [(t, 0) for t in _range(parts[0], model)]
    if len(parts) > 2:
        raise OrderError(f"thermal takes at most two orders (T, dT/dt), got '{orders}'",
                         column="orders", fix="use e.g. '2,2' or '1-3,1-2'")
    t_orders = _range(parts[0], model)
    r_orders = _range(parts[-1], model)
    if 0 in r_orders:
        raise OrderError("the thermal model needs a dT/dt order >= 1", column="orders",
                         fix="use --model bias-t for a polynomial in T only")
    return [(t, r) for t in t_orders for r in r_orders]


def model_spec(model: str, t_order: int, rate_order: int, opts: dict) -> ThermalSpec:
    gradient = opts.get("gradient") or ()
    if gradient is True:
        gradient = ("temperature_2", "temperature")
    if model == "bias-t" and (opts.get("extra") or gradient):
        raise FogbayesError("bias-t is a polynomial in one temperature channel",
                            column="model", fix="use --model thermal for extra channels")
    return check_spec(ThermalSpec(
        t_order=t_order, rate_order=rate_order, cross=bool(opts.get("cross", False)),
        extra=tuple(opts.get("extra") or ()), gradient=tuple(gradient),
        extra_order=int(opts.get("extra_order", 1)), temperature=str(opts.get("temperature") or "")))


def _lsq(spec: ThermalSpec, blocks):
    basis = thermal_basis(spec, blocks.z)
    if not (np.all(np.isfinite(blocks.y)) and np.all(np.isfinite(blocks.z))):
        raise NonFiniteError("the block means of the fit hold NaN or infinity", column="output",
                             fix="repair the non-finite samples or covariates first")
    if blocks.y.size < basis.n_terms + 2:
        raise TooShortError(f"{blocks.y.size} block means cannot fit {basis.n_terms} "
                            f"coefficients", column="output",
                            fix="record longer, average over shorter blocks or lower the order")
    return lstsq(design(blocks.z, basis), blocks.y, blocks.count.astype(float)), basis


def _bias(basis, coef, z) -> np.ndarray:
    return np.asarray(design(z, basis) @ np.asarray(coef))


def clamp_covariates(z: np.ndarray, basis, valid: dict) -> np.ndarray:
    """Covariates held inside the range the fit saw (a polynomial extrapolates wildly)."""
    lo = np.array([valid[n][0] for n in basis.names])
    hi = np.array([valid[n][1] for n in basis.names])
    return np.clip(z, lo, hi)


def _choose_order(specs, blocks, proc, criterion: str, seed: int, bayes_opts: dict):
    """The candidate with the best score: smallest RMS criterion (paper 000 eq. 11), or
    largest expected log predictive density by PSIS-LOO / WAIC under the posterior with
    AR noise (one posterior per candidate: slower, but honest for coloured noise)."""
    if criterion not in ("rms", "loo", "waic"):
        raise FogbayesError(f"unknown order criterion {criterion!r}", column="order_criterion",
                            fix="use 'rms' (paper 000), 'loo' or 'waic'")
    if len(specs) == 1:
        return specs[0], None
    if criterion == "rms":
        def residual(spec):
            fit, basis = _lsq(spec, blocks)
            return np.asarray(fit.residual), basis.n_terms

        choice = select_order(residual, specs)
        best, scores, label = choice.best, choice.scores, "rms (paper 000 eq. 11), smallest"
    else:
        scores = []
        for spec in specs:
            from .bayes import posterior_document  # NumPyro: only when asked

            post = posterior_document(blocks, thermal_basis(spec, blocks.z), proc, seed=seed,
                                      **bayes_opts)
            scores.append(post[criterion].get("elpd", float("-inf")))
        best, label = specs[int(np.argmax(scores))], f"elpd_{criterion} (AR noise), largest"
    return best, {"criterion": label, "candidates": [[s.t_order, s.rate_order] for s in specs],
                  "scores": scores, "best": [best.t_order, best.rate_order]}


def thermal_segments(rec, z):
    try:
        return segment_thermal(rec.time, z[:, 0])
    except FogbayesError:  # too short or irregular for the segmenter: full record only
        return []


def fit_recording(rec, *, model: str, orders: str | None = None, bayes: bool = False,
                  seed: int = 0, **options) -> dict:
    """Fit ``bias-t`` or ``thermal`` to a static thermal test; returns the fit document.

    Options: ``processing`` ("default" | "paper") and its overrides (``average_s``,
    ``temperature_average_s``, ``rate_method`` ("savgol" | "difference" | "paper"),
    ``rate_window_s``, ``outliers`` ("pauta" | "none"), ``n_sigma``); model structure
    (``cross``, ``extra`` channel names, ``gradient`` (True or (outer, inner)),
    ``extra_order``, ``temperature`` channel); posterior (``noise`` "ar" | "white" |
    "arma", ``ar_order``, ``ma_order``, ``num_warmup``, ``num_samples``, ``num_chains``,
    ``level``, ``bayes_average_s``); ``order_criterion`` ("rms" | "loo" | "waic") when
    ``orders`` has several candidates; ``windows`` for bias stability.
    """
    import fogbayes

    if model not in MODELS:
        raise FogbayesError(f"unknown thermal model '{model}'", column="model",
                            fix=f"use one of {', '.join(MODELS)}")
    proc = processing_of_options(model, options,
                                 set(_OTHER_KEYS) | set(_SPEC_KEYS) | set(_BAYES_KEYS))
    windows = tuple(options.get("windows", DEFAULT_WINDOWS))
    rate = rec.rate("deg/h")
    # gross errors (non-finite after the unit conversion, |rate| > 1e9 deg/h, > 1e3 robust
    # sigmas from the median) are flagged first and never reach a sum: one 1e308 cell would
    # make the least-squares variance and the 3-sigma rule's sigma infinite
    gross = gross_error_flags(rate, limit=RATE_LIMIT_DEG_H)
    if gross.count > rate.size // 2:
        raise NonFiniteError(f"{gross.count} of {rate.size} samples are non-finite or absurd "
                             f"(|rate| > {RATE_LIMIT_DEG_H:g} deg/h or far off the median)",
                             file=rec.meta.source, column="output",
                             fix="check the output unit (--output-unit) and the file")
    pre = gross.mask if gross.count else None
    if gross.count:
        rate = np.where(gross.mask, np.median(rate[~gross.mask]), rate)  # stand-ins, masked
    specs = [model_spec(model, t, r, options) for t, r in parse_orders(model, orders)]
    z = sample_covariates(rec, specs[0], proc)  # the same covariates for every order
    if not np.all(np.isfinite(z)):
        raise NonFiniteError("the covariates (temperature, dT/dt) hold NaN or infinity",
                             file=rec.meta.source, column="temperature",
                             fix="repair the temperature channels")
    blocks = fit_blocks(rec, rate, z, specs[0], proc, pre)

    bayes_opts = {k: options[k] for k in _BAYES_KEYS if k in options}
    spec, selection = _choose_order(specs, blocks, proc, options.get("order_criterion", "rms"),
                                    seed, bayes_opts)
    fit, basis = _lsq(spec, blocks)
    flags = gross if gross.count else None
    if proc.outliers == "pauta":
        flags = pauta_flags(rate - _bias(basis, fit.params, z), n_sigma=proc.n_sigma, mask=pre)
        if flags.count > gross.count:
            blocks = fit_blocks(rec, rate, z, spec, proc, flags.mask)
            fit, basis = _lsq(spec, blocks)
    coef = np.asarray(fit.params)
    if not (np.all(np.isfinite(coef)) and np.all(np.isfinite(np.asarray(fit.covariance)))):
        raise NonFiniteError("the least-squares fit gave non-finite coefficients or covariance",
                             file=rec.meta.source, column="output",
                             fix="check the recording for absurd values and the model order")
    lo, hi = blocks.z.min(axis=0), blocks.z.max(axis=0)
    valid = {name: (float(a), float(b)) for name, a, b in zip(basis.names, lo, hi)}
    from .compensate import compensate_bias  # (imports JAX; NumPy below 5e6 samples)

    after = compensate_bias(coef, clamp_covariates(z, basis, valid), rate, basis)  # as compensation does
    units = {"output": "deg/h", "T": "degC", "dT/dt": "degC/min"}
    warnings = []
    if not bool(fit.converged):
        warnings.append("the design is rank deficient: some covariate does not vary enough "
                        "(e.g. dT/dt in a record without ramps); coefficients are not identified")
    ident = identifiability(basis, lo, hi, conditioning(design(blocks.z, basis),
                                                        blocks.count.astype(float)))
    if not ident["identifiable"]:
        warnings.append(f"not identifiable: {ident['reason']}; the coefficients are meaningless")
    if gross.count:
        off = f" or > {gross.threshold:.3g} deg/h off the median" if np.isfinite(gross.threshold) else ""
        warnings.append(f"{gross.count} sample(s) with non-finite or absurd values (|rate| > "
                        f"{RATE_LIMIT_DEG_H:g} deg/h{off}) were flagged as outliers, left out "
                        "of the fit and replaced by the median in the metrics")
    doc = {
        "schema": FIT_SCHEMA, "model": model, "fogbayes_version": fogbayes.__version__,
        "converged": bool(fit.converged) and ident["identifiable"], "warnings": warnings,
        "input": {"source": rec.meta.source, "sensor_id": rec.meta.sensor_id, "unit": rec.unit,
                  "scale_factor": rec.scale_factor, "n": rec.n},
        "params": {"spec": spec._asdict(), **coefficient_document(
            basis, coef, np.asarray(fit.covariance), units=units, valid_range=valid)},
        "processing": proc._asdict(),
        "outliers": {"method": proc.outliers, "n_sigma": proc.n_sigma,
                     "count": 0 if flags is None else flags.count},
        "diagnostics": {"identifiability": ident},
        "fit": {"n_blocks": int(blocks.y.size), "n_params": basis.n_terms,
                "rms_criterion": rms_criterion(np.asarray(fit.residual), basis.n_terms),
                "residual_std": float(np.sqrt(fit.sigma2)), "dof": int(fit.dof),
                "stderr_note": "least-squares standard errors assume white block means; "
                               "see 'bayes' for intervals with AR noise"},
        "metrics": segment_report(rate, after, rec.time, thermal_segments(rec, z), windows=windows),
    }
    if selection:
        doc["order_selection"] = selection
    if bayes:
        from .bayes import posterior_document  # NumPyro: only when asked

        post = posterior_document(blocks, basis, proc, seed=seed, **bayes_opts)
        doc["bayes"] = post
        doc["converged"] = doc["converged"] and post["convergence"]["converged"]
        if not post["convergence"]["converged"]:
            doc["warnings"].append("the posterior sampler did not converge (see bayes.convergence)")
    return doc


def check_fit_document(fit: dict) -> None:
    if not isinstance(fit, dict) or fit.get("model") not in MODELS or "params" not in fit:
        raise FogbayesError(f"not a bias-t/thermal fit document (model={fit.get('model')!r})"
                            if isinstance(fit, dict) else "the fit document is not a JSON object",
                            column="model", fix="pass the JSON written by 'fogbayes fit'")
    validate_in_memory(fit)


def compensate_recording(rec, fit: dict) -> dict[str, np.ndarray]:
    """Compensated output (input unit) and 3-sigma outlier flags, one row per input row."""
    check_fit_document(fit)
    p = fit["params"]
    spec = ThermalSpec(**{k: tuple(v) if isinstance(v, list) else v for k, v in p["spec"].items()})
    proc = Processing(**fit["processing"])
    basis = basis_from_dict(p["basis"])
    z = sample_covariates(rec, spec, proc)
    if "valid_range" in p:
        z = clamp_covariates(z, basis, p["valid_range"])
    rate = rec.rate("deg/h")
    from .compensate import compensate_bias

    comp = compensate_bias(np.asarray(p["coef"], dtype=float), z, rate, basis)
    gross = gross_error_flags(comp, limit=RATE_LIMIT_DEG_H)  # e.g. a 1e308 cell
    flags = pauta_flags(comp, n_sigma=float(proc.n_sigma), mask=gross.mask if gross.count else None)
    out = convert_rate(comp, "deg/h", rec.unit, scale_factor=rec.scale_factor)
    return {"time": np.asarray(rec.time), "output": np.asarray(out, dtype=float),
            "outlier": flags.mask.astype(bool)}
