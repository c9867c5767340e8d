"""Allan deviation family with noise identification, EDF and chi-square intervals.

:func:`allan_deviation` picks the tau grid (:mod:`~fogbayes.stats.taus`), computes the
variances (:mod:`~fogbayes.stats.allan_blocked` for ``oadev`` on CPU, else
:mod:`~fogbayes.stats.allan_kernels`; 2-D input is a batch of sensors), identifies the noise
per tau (:mod:`~fogbayes.stats.noise_id`), and gives Greenhall's EDF
(:mod:`~fogbayes.stats.edf`) and the chi-square interval. NaN samples are gaps: every term
spanning one is excluded (``n_terms`` kept, ``excluded`` dropped); the EDF treats the kept
terms as one contiguous run.
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from typing import NamedTuple

import math

import numpy as np

from ..support.lazy import jax_on_cpu
from ..errors import FogbayesError, TooShortError
from .allan_blocked import allan_variance_fast
from .allan_result import AllanDeviation  # the result (total.py returns it too)
from .allan_stencils import KINDS, static_counts
from .edf import chi2_interval, edf_for_kind
from .noise_id import identify_alphas
from .taus import cluster_sizes


#: From this many samples on, a single record's noise identification runs on a thread
#: beside the variance computation (below it, the thread's start costs more than it saves).
PARALLEL_NOISE_ID = 1 << 18
_NOISE_ID = ThreadPoolExecutor(1, thread_name_prefix="fogbayes-noise-id")


def allan_deviation(y, fs: float, *, taus="octave", kind: str = "oadev", per_decade: int = 20,
                    m_max: int | None = None, ci: float = 0.9,
                    method: str = "auto", bias_corrected: bool = False) -> AllanDeviation:
    """Allan-family deviation of rate samples ``y`` (shape (n,) or (batch, n)) at rate ``fs``.

    Args:
        y: rate samples in any unit (the deviation has the same unit); NaN = missing.
        fs: sample rate in Hz (tau = m / fs).
        taus: grid name (``octave``, ``decade``, ``dense``, ``all``) or explicit cluster sizes.
        kind: ``oadev`` (overlapping Allan, default), ``adev``, ``mdev``, ``ohdev``, ``hdev``,
            ``tdev`` (time deviation tau MDEV / sqrt(3), NIST SP 1065 eq. 17: in the unit
            of ``y`` times seconds -- seconds for fractional frequency, deg/h * s = 1/3600
            deg for a gyro in deg/h; its intervals and noise types are the MDEV ones),
            or a total deviation handled by :func:`fogbayes.stats.total.total_deviation`:
            ``totdev`` (NIST SP 1065 eq. 25), ``mtotdev`` (eq. 27), ``ttotdev``
            (tau MTOTDEV / sqrt(3)), ``htotdev`` (Hadamard total, drift-free; OHDEV at
            m = 1), ``theo1`` (eq. 30; even m, tau = 0.75 m / fs), ``theobr`` (Theo1 times
            the record's mean AVAR/Theo1, Stable32) and ``theoh`` (OADEV below m = 0.2 n,
            TheoBR above: :mod:`~fogbayes.stats.theoh`), with their own EDF
            (:mod:`~fogbayes.stats.edf_total`); no NaN gaps for these, ``method`` is not
            used and ``taus`` takes the same grids.
        per_decade: points per decade of the ``dense`` grid.
        m_max: largest cluster size (default: Stable32's stop ratio, see ``taus``).
        ci: two-sided confidence of ``dev_low``/``dev_high`` (0.683 for Stable32's 1 sigma).
        method: ``auto`` (on CPU: ``oadev`` by the cache-blocked accumulators of
            :mod:`~fogbayes.stats.allan_blocked`, ``mdev``/``ohdev`` by the fused loops of
            :mod:`~fogbayes.stats.allan_fused`; otherwise the jitted kernels), ``blocked``
            (those accumulators on any backend; ``oadev`` only), or a kernel path of
            :func:`~fogbayes.stats.allan_kernels.allan_sums` (``direct``, ``chunked``,
            ``mapped``).
        bias_corrected: total kinds only: remove the estimator's bias for the identified
            noise type (``theo1``: to AVAR at tau = 0.75 m / fs; ``htotdev``: Stable32's
            Htotvar/Hvar factors; ``totdev``: flicker and random-walk FM), see
            :func:`~fogbayes.stats.total.total_deviation`.
    """
    if kind in ("totdev", "mtotdev", "ttotdev", "htotdev", "theo1", "theobr",
                "theoh"):  # total family
        from .total import total_deviation

        return total_deviation(y, fs, taus=taus, kind=kind, ci=ci, m_max=m_max,
                               per_decade=per_decade, bias_corrected=bias_corrected)
    if bias_corrected:
        raise FogbayesError(f"bias_corrected applies to the total kinds, not {kind}",
                            argument="bias_corrected",
                            fix="use kind='totdev', 'htotdev' or 'theo1', or leave it out")
    if kind == "tdev":  # TDEV^2 = tau^2 Mod AVAR / 3: the modified variance, rescaled
        r = allan_deviation(y, fs, taus=taus, kind="mdev", per_decade=per_decade, m_max=m_max,
                            ci=ci, method=method)
        f = r.tau / math.sqrt(3.0)
        return r._replace(kind="tdev", var=r.var * f ** 2, dev=r.dev * f,
                          dev_low=r.dev_low * f, dev_high=r.dev_high * f)
    y = np.asarray(y, dtype=float)
    if y.ndim not in (1, 2):
        raise FogbayesError(f"rate data must be 1-D (or 2-D for a batch), got shape {y.shape}",
                            fix="pass one sensor as (n,) or a batch as (sensors, n)")
    if kind not in KINDS:
        raise FogbayesError(f"unknown deviation '{kind}'",
                            fix=f"use one of {', '.join(KINDS)}, tdev, totdev, mtotdev, "
                                "ttotdev, htotdev, theo1, theobr, theoh")
    if not (np.isfinite(fs) and fs > 0):
        raise FogbayesError(f"sample rate must be positive and finite, got {fs}",
                            fix="pass fs in Hz")
    n = y.shape[-1]
    if n < 3:
        raise TooShortError(f"the Allan deviation needs at least 3 samples, got {n}",
                            fix="record longer")
    n_missing = 0
    if not np.isfinite(np.add.reduce(y, axis=-1)).all():  # else: one pass says all finite
        missing = ~np.isfinite(y)
        if np.isinf(y).any():
            raise FogbayesError("rate data contain +-inf", fix="mark missing samples as NaN")
        n_missing = int(missing.sum())
        if missing.all(axis=-1).any():
            raise TooShortError("a sensor has no finite sample", fix="check the data")
    if method == "blocked" and kind != "oadev":
        raise FogbayesError(f"method 'blocked' computes oadev only, not {kind}", argument="method",
                            fix="use method='auto' for other kinds")
    ms = _grid(n, taus, kind, per_decade, m_max)
    # The noise identification does not need the variances, nor does the EDF of a record
    # without gaps (its term counts are known): on a long single record both run on a
    # second thread while the variances are computed (the compiled loops release the GIL).
    worker = y.ndim == 1 and n >= PARALLEL_NOISE_ID
    if worker and not n_missing:
        early = _NOISE_ID.submit(_edf, y, ms, static_counts(n, ms, kind), kind)
        alphas = None
    else:
        early = None
        alphas = _NOISE_ID.submit(identify_alphas, y, ms, kind=kind) if worker else None
    if kind == "oadev" and method in ("auto", "blocked") and (
            method == "blocked" or jax_on_cpu()):
        # CPU: the cache-blocked NumPy accumulators (Haar pyramid on octave grids), the
        # same estimator to ~1e-12 and 2-3x faster than the XLA kernels here (allan_blocked)
        var, count = allan_variance_fast(y, ms)
    elif kind in ("mdev", "ohdev") and method == "auto" and jax_on_cpu():
        # CPU: one fused compiled pass per tau from the phase (allan_fused), ~6-8x the
        # XLA kernels here; a batch runs row by row
        from .allan_fused import mod_hadamard_variance

        rows = [mod_hadamard_variance(r, ms, kind) for r in (y if y.ndim == 2 else [y])]
        var = np.stack([r[0] for r in rows]) if y.ndim == 2 else rows[0][0]
        count = np.stack([r[1] for r in rows]) if y.ndim == 2 else rows[0][1]
    else:
        from .allan_kernels import allan_variance

        var, count = allan_variance(y, ms, kind=kind, gaps=bool(n_missing),
                                    method="auto" if method == "blocked" else method)
    var, count = np.asarray(var), np.asarray(count)
    full = static_counts(n, ms, kind)
    if n_missing and (count == 0).any():
        keep = (count > 0).all(axis=0) if count.ndim == 2 else count > 0
        ms = tuple(np.asarray(ms)[keep].tolist())
        var, count, full = var[..., keep], count[..., keep], full[keep]
        if not ms:
            raise TooShortError("every cluster touches a gap", fix="use shorter taus or fill fewer gaps")
        if alphas is not None:  # identified on the full grid: keep the same taus
            alphas = _Done(alphas.result()[keep])
    if early is not None:  # no gaps: the counts the worker used are the counts
        alpha, edf = early.result()
    else:
        alpha, edf = _edf(y, ms, count, kind, alphas=None if alphas is None else alphas.result())
    lo, hi = chi2_interval(var, edf, ci)
    excluded = full - count
    note = ("no gaps" if not n_missing else
            f"{n_missing} missing (NaN) samples; every term touching one was excluded "
            f"({int(excluded.sum())} terms in all); EDF computed for the kept count")
    return AllanDeviation(kind, float(fs), np.asarray(ms) / fs, np.asarray(ms), var,
                          np.sqrt(var), count, excluded, alpha, edf, np.sqrt(lo), np.sqrt(hi),
                          float(ci), int(n), n_missing, note)


def _grid(n, taus, kind, per_decade, m_max) -> tuple[int, ...]:
    if isinstance(taus, str):
        return cluster_sizes(n, taus, per_decade=per_decade, m_max=m_max, kind=kind)
    ms = np.unique(np.asarray(taus, dtype=np.int64))
    span = 3 if kind in ("mdev", "ohdev", "hdev") else 2
    if ms.size == 0 or ms[0] < 1 or span * ms[-1] > n:
        raise TooShortError(f"cluster sizes must lie in 1..{n // span} for {n} samples",
                            argument="taus", fix="pass smaller cluster sizes (samples, not s)")
    return tuple(int(m) for m in ms)


class _Done(NamedTuple):
    value: np.ndarray

    def result(self) -> np.ndarray:
        return self.value


def _edf(y, ms, count, kind, alphas=None):
    """Noise ID (unless given) and EDF per tau (per sensor for a batch)."""
    if y.ndim == 2:
        parts = [_edf(row, ms, c, kind) for row, c in zip(y, count)]
        return np.stack([p[0] for p in parts]), np.stack([p[1] for p in parts])
    alpha = identify_alphas(y, ms, kind=kind) if alphas is None else np.asarray(alphas)
    # with gaps, the EDF of a contiguous record that would give the kept number of terms
    edf = np.array([edf_for_kind([a], [m], int(round(_n_for_count(c, m, kind))), kind)[0]
                    for a, m, c in zip(alpha, ms, count)])
    return alpha, edf


def _n_for_count(count: float, m: int, kind: str) -> float:
    """Record length whose gap-free term count equals ``count`` (inverts static_counts)."""
    if kind == "mdev":
        return count + 3 * m - 2
    k = 3 if kind in ("ohdev", "hdev") else 2
    if kind in ("adev", "hdev"):
        return (count - 1) * m + 1 + k * m - 1
    return count + k * m - 1
