"""Workflow for the ``allan`` model: Allan deviation and five-term noise fit of a Recording.

``fit_recording``: the rate in deg/h on a uniform grid (gaps NaN), the OADEV with Greenhall EDF
and 90 % intervals (:func:`fogbayes.stats.allan.allan_deviation`), the noise fit on octave taus
(GLS :func:`fogbayes.allan.fit.fit_wls`, or :mod:`fogbayes.allan.bayes` with ``bayes=True``;
short taus dropped by :func:`fogbayes.allan.fit.fit_range`), paper 002's fit and IEEE 952
readouts. Options: ``taus``, ``per_decade``, ``select``, sampler sizes, ``kind`` /
``bias_corrected`` (a second deviation under ``deviation``), ``prior``
(:mod:`fogbayes.inference.datasheet`, recorded under ``fit.prior``). ``compensate_recording`` refuses.
"""

from __future__ import annotations

import numpy as np

from .. import __version__
from ..data.documents import FIT_SCHEMA
from ..errors import FogbayesError
from .data import prepare
from .fit import AllanFit, fit_paper_lsq, fit_range
from .readout import slope_readouts
from .model import ARCSEC_IN_URAD, TERMS, UNITS, adev, term_avar
from ..stats.allan import allan_deviation

MODELS = ("allan",)
CI = 0.9
_OPTIONS = ("taus", "per_decade", "select", "num_warmup", "num_samples", "num_chains", "kind",
            "bias_corrected")
_ALL_TAUS_MAX = 200_000


class AllanInputError(FogbayesError):
    """The recording cannot be analysed with the Allan variance as given."""


def uniform_rate(rec, *, tolerance: float = 0.05) -> tuple[np.ndarray, float, int]:
    """The rate in deg/h on a uniform grid (NaN where samples are missing), fs, NaN count.

    Each time stamp must sit within ``tolerance`` sample periods of the grid; gaps (missing
    samples) are allowed and become NaN.
    """
    rate = np.asarray(rec.rate("deg/h"), dtype=float)
    fs = float(rec.sample_rate)
    pos = (rec.time - rec.time[0]) * fs
    k = np.rint(pos).astype(np.int64)
    off = np.abs(pos - k)
    bad = np.flatnonzero((off > tolerance) | (np.diff(k, prepend=-1) < 1))
    if bad.size:
        raise AllanInputError(
            f"time stamps are not on a uniform {1 / fs:g} s grid (first off-grid row: "
            f"t = {rec.time[bad[0]]!r})", file=rec.meta.source, column="time", row=int(bad[0]),
            fix="resample to a constant rate first (the Allan variance needs uniform sampling; "
                "missing samples are fine)")
    if k[-1] + 1 > 20 * rec.n:
        raise AllanInputError(
            f"gaps make the record {(k[-1] + 1) / rec.n:.0f} x longer than its {rec.n} samples",
            file=rec.meta.source, column="time", fix="analyse the continuous segments separately")
    y = np.full(int(k[-1]) + 1, np.nan)
    y[k] = rate
    return y, fs, int(y.size - rec.n)


def _term_doc(est, present: bool = True) -> dict:
    d = {"value": est.value, "low": est.low, "high": est.high, "unit": est.unit,
         "present": bool(present)}
    if est.unit == UNITS["Q"]:  # quantization: also in urad
        d.update(value_urad=est.value * ARCSEC_IN_URAD, low_urad=est.low * ARCSEC_IN_URAD,
                 high_urad=est.high * ARCSEC_IN_URAD)
    return d


def _curves(params, tau_lo: float, tau_hi: float) -> dict:
    grid = np.geomspace(tau_lo, tau_hi, 120)
    parts = np.sqrt(np.asarray(term_avar(tuple(params), grid)))
    return {"tau": grid, "total": np.asarray(adev(tuple(params), grid)),
            "terms": {t: parts[i] for i, t in enumerate(TERMS) if params[i] > 0}}


def _fit_doc(fit: AllanFit, terms: dict, data, extra: dict) -> dict:
    return {"method": fit.method, "terms": terms, "converged": fit.converged,
            "fit_tau": data.tau, "fit_adev": np.sqrt(data.avar),
            "curves": _curves(fit.params, data.tau[0], data.tau[-1]), **extra}


def _wls_doc(fit: AllanFit, data) -> dict:
    terms = {t: _term_doc(e, e.low > 0) for t, e in fit.terms.items()}
    return _fit_doc(fit, terms, data, {"diagnostics": {
        "chi2": fit.info["chi2"], "dof": fit.info["dof"], "gof_p": fit.info["gof_p"],
        "dispersion": fit.info["dispersion"],
        # False: the GLS weights cycled between solutions; the likeliest was kept
        "weights_settled": fit.info["weights_settled"], "passes": fit.info["passes"],
        "interval": "Gauss-Newton in log space; low = 0 when dropping the term raises chi2 "
                    "by < 2.71 (profile likelihood)"}})


def _bayes_doc(data, seed: int, select: bool, sampler: dict, prior=None) -> dict:
    from . import bayes as ab

    if select:
        sel = ab.select_terms(data, seed=seed, prior=prior, **sampler)
        post, rep = sel.selected, ab.reported_terms(sel)
        terms = {t: _term_doc(e, present) for t, (e, present) in rep.items()}
        rule = (f"drop a term when removing it costs < {ab.ELPD_THRESHOLD:g} elpd (PSIS-LOO; "
                "drop-one models with a quarter of the draws, at least 500 a chain; the selected "
                "model with all)")
        if prior is not None:
            rule += "; terms the datasheet prior gives are kept"
        extra = {"selection": {"present": list(sel.present), "comparisons": sel.table,
                               "rule": rule}}
    else:
        post = ab.fit_bayes(data, seed=seed, prior=prior, **sampler)
        terms = {t: _term_doc(e) for t, e in post.fit.terms.items()}
        extra = {}
    if prior is not None:
        extra["prior"] = prior.record()
    lo, med, hi = ab.posterior_band(post, _curves(post.fit.params, data.tau[0],
                                                  data.tau[-1])["tau"], ci=CI)
    plo, phi = ab.predictive_band(post, ci=CI, seed=seed)
    extra.update(diagnostics=post.diagnostics,
                 band={"tau": _curves(post.fit.params, data.tau[0], data.tau[-1])["tau"],
                       "adev_low": lo, "adev_median": med, "adev_high": hi},
                 predictive={"tau": data.tau, "adev_low": plo, "adev_high": phi})
    return _fit_doc(post.fit, terms, data, extra)


def _comparison(data, dev) -> dict:
    paper = fit_paper_lsq(data)
    ro = slope_readouts(dev.tau, dev.dev, dev.dev_low, dev.dev_high)
    return {"paper_lsq": {"terms": {t: _term_doc(e) for t, e in paper.terms.items()},
                          "C": paper.info["C"]},
            "ieee952_readout": {t: (None if e is None else _term_doc(e)) for t, e in ro.items()}}


def fit_recording(rec, *, model: str = "allan", orders: str | None = None, bayes: bool = False,
                  seed: int = 0, prior=None, **options) -> dict:
    """Allan deviation and five-term noise fit of ``rec`` as a JSON-able document
    (``prior``: a datasheet prior for the posterior, ``bayes=True`` only; module doc)."""
    if prior is not None:
        from ..inference.datasheet import as_prior

        if not bayes:
            raise FogbayesError("a datasheet prior needs the posterior fit", column="prior",
                                fix="fit with bayes=True (fogbayes allan --bayes --prior "
                                    "PRIOR.json); the least-squares fit has no prior")
        prior = as_prior(prior)
    if model not in MODELS:
        raise FogbayesError(f"the Allan workflow fits model 'allan', not '{model}'",
                            column="model", fix="use --model allan")
    unknown = sorted(set(options) - set(_OPTIONS))
    if unknown:
        raise FogbayesError(f"unknown option(s) {unknown} for model allan", column="--option",
                            fix=f"use only {', '.join(_OPTIONS)}")
    if orders not in (None, ""):
        raise FogbayesError("the allan model has no orders", column="orders",
                            fix="leave --order out (terms are selected with --bayes)")
    y, fs, missing = uniform_rate(rec)
    if options.get("taus") == "all" and y.size > _ALL_TAUS_MAX:
        raise FogbayesError(
            f"the 'all' tau grid on {y.size} samples costs ~n^2/4 = {y.size**2 / 4:.1e} "
            "operations", column="taus",
            fix=f"use --taus dense (e.g. 20 per decade); 'all' is for up to {_ALL_TAUS_MAX} samples")
    dev = allan_deviation(y, fs, taus=options.get("taus", "octave"),
                          per_decade=int(options.get("per_decade", 20)), ci=CI)
    if not np.any(dev.var > 0):  # a log of zero: nothing to fit, and no fit can say so
        raise AllanInputError(
            f"the output is constant ({np.nanmin(y):g} {rec.unit} at every sample): the Allan "
            "variance is zero at every tau and there is no noise to fit",
            file=rec.meta.source, column="output",
            fix="check the column (a stuck, saturated or disconnected sensor?) or pass "
                "the gyro's output column with --column")
    full = prepare(y, fs)
    data, gls, left_out = fit_range(full)
    sampler = {k: int(options[k]) for k in ("num_warmup", "num_samples", "num_chains")
               if k in options}
    fit = (_bayes_doc(data, seed, bool(options.get("select", True)), sampler, prior) if bayes
           else _wls_doc(gls, data))
    fit["range"] = {"tau_min": data.tau[0], "tau_max": data.tau[-1], "taus_left_out": left_out,
                    "rule": "shortest octave taus left out while the GLS goodness of fit has "
                            "p < 1e-3 (sensor filtering), at most a third of them"}
    params = {t: (fit["terms"][t]["value"] if t in fit["terms"] else 0.0) for t in TERMS}
    extra = _second_deviation(y, fs, options)
    doc = {"schema": FIT_SCHEMA, "model": "allan", "fogbayes_version": __version__,
            "sensor_id": rec.meta.sensor_id,
            "source": rec.meta.source, "n": int(y.size), "fs": fs, "unit": "deg/h",
            "input_unit": rec.unit, "ci": CI, "taus": options.get("taus", "octave"),
            "gaps": {"missing_samples": missing, "note": dev.note},
            "tau": dev.tau, "adev": dev.dev, "adev_low": dev.dev_low,
            "adev_high": dev.dev_high, "edf": dev.edf, "alpha": dev.alpha,
            "n_terms": dev.n_terms, "fit": fit, "comparison": _comparison(full, dev),
            "params": params, "converged": bool(fit["converged"])}
    if extra:
        doc["deviation"] = extra
    return doc


def _second_deviation(y, fs, options) -> dict | None:
    """The ``kind``/``bias_corrected`` options (module doc): None for the plain OADEV."""
    kind = str(options.get("kind", "oadev"))
    flag = options.get("bias_corrected", False)
    if isinstance(flag, str):
        if flag.lower() not in ("true", "false", "1", "0", "yes", "no"):
            raise FogbayesError(f"bias_corrected={flag!r} is not true or false",
                                column="bias_corrected",
                                fix="give --option bias_corrected=true (or false)")
        flag = flag.lower() in ("true", "1", "yes")
    if kind == "oadev" and not flag:
        return None
    dev = allan_deviation(y, fs, taus=options.get("taus", "octave"), kind=kind, ci=CI,
                          per_decade=int(options.get("per_decade", 20)),
                          bias_corrected=bool(flag))
    return {"kind": dev.kind, "bias_corrected": bool(flag), "tau": dev.tau, "dev": dev.dev,
            "dev_low": dev.dev_low, "dev_high": dev.dev_high, "edf": dev.edf,
            "alpha": dev.alpha, "n_terms": dev.n_terms, "note": dev.note}


def compensate_recording(rec, fit: dict) -> dict:
    """An Allan model describes random noise: there is nothing to subtract."""
    raise FogbayesError(
        "an Allan (noise) model has nothing to compensate: it describes random noise, "
        "not a deterministic error", field="model",
        fix="compensate with a bias-t, thermal or composite fit (fogbayes fit --model thermal)")
