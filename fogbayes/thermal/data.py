"""From a Recording to the data a thermal bias fit needs: block means and per-sample covariates.

``"paper"``: paper 004 (1 s rate, 10 s temperature held, backward difference of 10 s means,
:func:`fogbayes.preprocess.paper004_smoothing`), Pauta on the residuals. ``"default"``: the same
rate blocks and flags, 1 s temperature, centred 60 s Savitzky-Golay rate
(benchmarks/RESULTS_thermal.md). Compensation uses the same estimator per sample.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..errors import FogbayesError, MissingColumnError
from .model import ThermalSpec, thermal_covariates
from ..preprocess import block_average, paper004_smoothing


class Processing(NamedTuple):
    """How a recording is turned into fit data (see the module doc)."""

    mode: str = "default"
    average_s: float = 1.0
    temperature_average_s: float = 10.0
    rate_method: str = "savgol"
    rate_window_s: float = 60.0
    outliers: str = "pauta"
    n_sigma: float = 3.0
    rate_gap_factor: float | None = None  # None: gaps as preprocess defines them


def processing_of_options(model: str, options: dict, other_keys) -> Processing:
    """The :class:`Processing` of a fit's ``**options`` (``processing`` mode plus the
    overrides), refusing any key that is neither a processing field nor in ``other_keys``."""
    known = set(Processing._fields[1:]) | {"processing"} | set(other_keys)
    bad = sorted(set(options) - known)
    if bad:
        raise FogbayesError(f"unknown option(s) {bad} for model {model}", column="options",
                            fix=f"use {', '.join(sorted(known))}")
    return make_processing(options.get("processing", "default"),
                           **{k: options[k] for k in Processing._fields[1:] if k in options})


def make_processing(mode: str = "default", **overrides) -> Processing:
    """The defaults of ``mode`` ("default" or "paper") with explicit overrides."""
    if mode == "paper":
        base = Processing("paper", 1.0, 10.0, "paper", 10.0, "pauta", 3.0, None)
    elif mode == "default":
        base = Processing()
    else:
        raise FogbayesError(f"unknown processing mode {mode!r}", column="processing",
                            fix="use 'default' or 'paper'")
    bad = set(overrides) - set(Processing._fields)
    if bad:
        raise FogbayesError(f"unknown processing option(s) {sorted(bad)}", column="processing",
                            fix=f"use {', '.join(Processing._fields[1:])}")
    proc = base._replace(**{k: v for k, v in overrides.items() if v is not None})
    if proc.outliers not in ("pauta", "none"):
        raise FogbayesError(f"unknown outlier rule {proc.outliers!r}", column="outliers",
                            fix="use 'pauta' (3-sigma, paper 004) or 'none'")
    return proc


class Blocks(NamedTuple):
    """Fit data: block time (m,), mean rate y (m,) deg/h, covariates z (m, c), samples (m,)."""

    time: np.ndarray
    y: np.ndarray
    z: np.ndarray
    count: np.ndarray


def sample_covariates(rec, spec: ThermalSpec, proc: Processing) -> np.ndarray:
    """Covariates (n, c) at every sample (used for residuals, outliers and compensation)."""
    return thermal_covariates(rec.time, rec.temperatures, rec.temperature_names, spec,
                              rate_method=proc.rate_method, rate_window_s=proc.rate_window_s,
                              rate_gap_factor=proc.rate_gap_factor, source=rec.meta.source)


def fit_blocks(rec, rate: np.ndarray, z: np.ndarray, spec: ThermalSpec, proc: Processing,
               mask: np.ndarray | None) -> Blocks:
    """Block means for the fit; flagged samples (``mask``) are left out of the means."""
    if proc.mode == "paper":
        return _paper_blocks(rec, rate, spec, proc, mask)
    b = block_average(np.column_stack([rate, z]), proc.average_s, time=rec.time, mask=mask)
    keep = b.count > 0
    return Blocks(b.time[keep], b.mean[keep, 0], b.mean[keep, 1:], b.count[keep])


def _index(rec, name: str) -> int:
    names = list(rec.temperature_names)
    if not names:
        raise MissingColumnError("the recording has no temperature channel",
                                 file=rec.meta.source, column="temperature",
                                 fix="add a 'temperature' column in deg C")
    if name == "":
        return 0
    if name not in names:
        raise MissingColumnError(f"no temperature channel '{name}' (have {names})",
                                 file=rec.meta.source, column=name,
                                 fix="name an existing channel or add the column")
    return names.index(name)


def _paper_blocks(rec, rate, spec: ThermalSpec, proc: Processing, mask) -> Blocks:
    """Paper 004's smoothing: 1 s rate means, 10 s temperature means and their differences."""
    in_deg_h = rec.replace(output=rate, unit="deg/h", scale_factor=None)
    sm = paper004_smoothing(in_deg_h, mask=mask, rate_window_s=proc.average_s,
                            temperature_window_s=proc.temperature_average_s, align="hold")
    temps = sm.recording.temperatures
    i = _index(rec, spec.temperature)
    cols = [temps[:, i]]
    if spec.rate_order > 0:
        cols.append(60.0 * sm.temperature_rate[:, i])  # deg C/s -> deg C/min
    cols += [temps[:, _index(rec, nm)] for nm in spec.extra]
    if spec.gradient:
        cols.append(temps[:, _index(rec, spec.gradient[0])] - temps[:, _index(rec, spec.gradient[1])])
    return Blocks(sm.recording.time, sm.recording.output, np.column_stack(cols), sm.count)


def coarser_blocks(blocks: Blocks, window_s: float) -> Blocks:
    """Fit blocks averaged again over ``window_s`` (for the posterior: fewer, longer blocks)."""
    data = np.column_stack([blocks.y, blocks.z])
    b = block_average(data, window_s, time=blocks.time, partial="drop")
    keep = b.count > 0
    return Blocks(b.time[keep], b.mean[keep, 0], b.mean[keep, 1:], b.count[keep])
