"""Compensate a record larger than memory, chunk by chunk, into a file.

:func:`compensate_stream` does what :func:`fogbayes.thermal.workflow.compensate_recording` and
:func:`fogbayes.composite.workflow.compensate_recording` do, with the compiled CPU compensators:
bias-t / thermal ``y - X(z) @ coef`` on clamped covariates (:mod:`.covariates`), 3-sigma flags by
:mod:`.pauta` (one pass per iteration); composite: operating time carried across chunks and the
Halley inversion. Equal to the in-memory path on CPU (bit for bit, or to rounding for FFT
Savitzky-Golay windows). Columns: ``time``, ``output`` (``rate``), ``outlier``.
"""

from __future__ import annotations

from functools import partial

from pathlib import Path
from typing import NamedTuple

import numpy as np

from ..errors import FogbayesError, UnitError
from ..preprocess._checks import GAP_FACTOR
from ..data.units import convert_rate
from .covariates import covariate_chunks, make_plan
from .pauta import stream_pauta
from .scan import scan_time
from .stability import StreamStability
from .sources import DEFAULT_ROWS, RecordSource, open_source
from .writers import check_sink, open_sink


class StreamCompensation(NamedTuple):
    """What was written and how."""

    path: Path
    n: int
    columns: tuple
    outliers: int        # rows flagged (3 sigma, or not invertible for composite)
    threshold: float     # last 3-sigma threshold, deg/h (NaN for composite)
    iterations: int      # Pauta iterations (0 for composite)
    passes: int          # passes over the input, scan included
    metrics: dict | None = None  # metrics=True, bias-t/thermal: bias stability before/after


def compensate_stream(source, fit: dict, out, *, rows: int = DEFAULT_ROWS, flags: bool = True,
                      include_time: bool = True, metrics: bool = False,
                      dtype=np.float64) -> StreamCompensation:
    """Compensate ``source`` (a :class:`RecordSource` or path) with ``fit`` into ``out``.

    Args:
        fit: the fit document of ``fogbayes fit`` (bias-t, thermal or composite).
        out: a directory (``<column>.npy`` each), ``.npz`` or ``.parquet``.
        rows: rows per chunk (memory: a few arrays of this many rows, plus the halo).
        flags: compute the 3-sigma outlier column (bias-t/thermal; extra passes).
        include_time: copy the time column into the output. Without it a bias-t record's
            time column is neither read nor validated (nothing else needs it).
        metrics: bias-t/thermal: also the bias and bias stability before/after
            (:mod:`.stability`, the in-memory ``stability_report``; reads the time column).
        dtype: dtype of the compensated column (float64 = the in-memory result).
    """
    check_sink(out)  # an output it could not write or replace: refused before any pass
    if not isinstance(source, RecordSource):
        source = open_source(source)
    model = fit.get("model") if isinstance(fit, dict) else None
    if model in ("bias-t", "thermal"):
        return _thermal(source, fit, out, rows, flags, include_time, metrics, dtype)
    if model == "composite":
        return _composite(source, fit, out, rows, include_time, dtype)
    raise FogbayesError(f"cannot compensate with model {model!r}", column="model",
                        fix="pass a bias-t, thermal or composite fit document")


def _thermal(source, fit, out, rows, flags, include_time, metrics, dtype):
    from ..thermal.compensate_loops import compensate_into
    from ..models.basis_document import basis_from_dict
    from ..thermal.model import ThermalSpec
    from ..thermal.data import Processing
    from ..thermal.workflow import check_fit_document, clamp_covariates

    check_fit_document(fit)
    p = fit["params"]
    spec = ThermalSpec(**{k: tuple(v) if isinstance(v, list) else v for k, v in p["spec"].items()})
    proc = Processing(**fit["processing"])
    basis = basis_from_dict(p["basis"])
    source.require("output")
    if include_time or metrics:
        source.require("time")
    scan = None
    if spec.rate_order > 0:
        scan = scan_time(source, rows=rows, gap_factor=proc.rate_gap_factor or GAP_FACTOR)
    # the report's blocks are cut at gaps by the default rule, whatever the fit's rate rule
    metric_scan = None
    if metrics:
        metric_scan = scan if scan is not None and scan.gap_factor == GAP_FACTOR \
            else scan_time(source, rows=rows)
    plan = make_plan(source, scan, spec, rate_method=proc.rate_method,
                     rate_window_s=proc.rate_window_s)
    coef = np.asarray(p["coef"], dtype=float)
    valid = p.get("valid_range")
    # Chunks start and end in host memory: the compiled CPU loop, whatever JAX's default
    # device (on an H200 machine XLA on the GPU took 18.2 s and 4.3 GB of peak memory for
    # 2e8 samples, the loop 10.2 s and 0.7 GB: benchmarks/RESULTS_gpu.md). "loop": many
    # chunks, never the one-off NumPy path.
    f = partial(compensate_into, basis, method="loop")
    fields = ("time", "output", "temperatures") if include_time or scan or metrics \
        else ("output", "temperatures")

    def compensated():
        for ch, z in covariate_chunks(source, plan, scan, rows, fields=fields):
            if valid is not None:
                z = clamp_covariates(z, basis, valid)
            rate = np.asarray(convert_rate(ch.output, source.unit, "deg/h",
                                           scale_factor=source.scale_factor), dtype=float)
            yield ch, f(coef, z, rate)

    passes = 0 if scan is None else scan.passes
    if metric_scan is not None and metric_scan is not scan:
        passes += metric_scan.passes
    stability = None if metric_scan is None else StreamStability(metric_scan)
    pauta = None
    if flags:
        pauta = stream_pauta(lambda: (c for _, c in compensated()), n_sigma=float(proc.n_sigma))
        passes += pauta.passes
    cols = {"time": np.float64} if include_time else {}
    cols.update(output=dtype, outlier=np.bool_)
    n_out = 0
    with open_sink(out, source.n, cols) as sink:  # an exception removes the partial output
        for ch, comp in compensated():
            mask = pauta.flags(comp) if pauta is not None else np.zeros(comp.size, bool)
            n_out += int(mask.sum())
            if stability is not None:
                before = convert_rate(ch.output, source.unit, "deg/h",
                                      scale_factor=source.scale_factor)
                stability.add(ch.start, ch.time, before, comp)
            y = convert_rate(comp, "deg/h", source.unit, scale_factor=source.scale_factor)
            part = {"output": np.asarray(y, dtype=float), "outlier": mask}
            if include_time:
                part["time"] = ch.time
            sink.write(**part)
        path = sink.close()
    return StreamCompensation(path, source.n, tuple(cols), n_out,
                              float(pauta.threshold) if pauta else float("nan"),
                              int(pauta.iterations) if pauta else 0, passes + 1,
                              None if stability is None else stability.report())


def _composite(source, fit, out, rows, include_time, dtype):
    from ..preprocess.operating_time import operating_time_chunk
    from ..composite.workflow import compensator_from_fit

    unit = (fit.get("input") or {}).get("unit")
    if unit is not None and source.unit != unit:
        raise UnitError(f"the recording's output is in {source.unit} but the fit was made in "
                        f"{unit}", file=source.source, column="output",
                        fix=f"open the recording with unit {unit}")
    source.require("time", "output", "temperature")
    comp = compensator_from_fit(fit, host=True)  # host chunks: the CPU loop (see _thermal)
    conv = fit.get("operating_time", "cell")
    by_cell = conv == "cell" and source.input_rate_name is not None
    fields = ("time", "output", "temperatures") + (("input_rate",) if by_cell else ())
    cols = {"time": np.float64} if include_time else {}
    cols.update(rate=dtype, outlier=np.bool_)
    carry = origin_t = None
    n_out = 0
    with open_sink(out, source.n, cols) as sink:  # an exception removes the partial output
        for ch in source.chunks(rows, fields=fields):
            t = ch.time
            if by_cell:  # fogbayes.preprocess.operating_time, carried across chunks
                op, carry = operating_time_chunk(t, ch.input_rate, carry)
            else:
                origin_t = float(t[0]) if origin_t is None else origin_t
                op = t - origin_t
            U, T = ch.output, ch.temperatures[:, 0]
            rate, ok = comp(U, T, op)
            mask = ~np.asarray(ok)
            n_out += int(mask.sum())
            part = {"rate": np.asarray(rate, dtype=float), "outlier": mask}
            if include_time:
                part["time"] = t
            sink.write(**part)
        path = sink.close()
    return StreamCompensation(path, source.n, tuple(cols), n_out, float("nan"), 0, 1)
