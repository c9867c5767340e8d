"""Total deviations TOTDEV, MTOTDEV, TTOTDEV, HTOTDEV and Theo1 with EDF and chi-square intervals.

:func:`total_deviation` returns an :class:`~fogbayes.stats.allan_result.AllanDeviation` (also
reached through :func:`~fogbayes.stats.allan.allan_deviation`). NIST SP 1065: ``totdev`` eq. 25
(phase reflected oddly at both ends, ``n_terms = N - 2``); ``mtotdev`` eq. 27 (``3m``-point
subsequences, half-average slope removed, even reflection to ``9m``); ``ttotdev`` eq. 28
(tau MTOTDEV / sqrt 3); ``htotdev`` sec. 5.2.14 (MTOTDEV's construction on the rate, ``bias_corrected``
by :data:`~fogbayes.stats.edf_total.HTOTVAR_BIAS`); ``theo1`` (:mod:`~fogbayes.stats.theo1`,
tau = 0.75 m tau0); ``theobr`` and ``theoh`` (Theo1 times one AVAR/Theo1 factor per record,
and its hybrid with OADEV: :mod:`~fogbayes.stats.theoh`). Noise per tau:
:func:`~fogbayes.stats.noise_id.identify_alphas` (MTOTDEV, TTOTDEV, HTOTDEV below 30 cluster
means: B1 and R(n), :mod:`~fogbayes.stats.noise_id_b1`); EDF: :mod:`~fogbayes.stats.edf_total`;
interval :func:`~fogbayes.stats.edf.chi2_interval`. NaN is refused.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import FogbayesError, TooShortError
from .allan_result import AllanDeviation
from .edf import chi2_interval
from .edf_total import (edf_for_total_kind, htotvar_bias_ratio, theo1_bias_ratio,
                         totvar_bias_ratio)
from .noise_id import MIN_POINTS, identify_alphas
from .noise_id_b1 import b1_rn_alpha
from .total_taus import total_grid, total_limits
from .theo1 import theo1_variance
from .total_loops import mtotvar_sums, phase_samples, prefix2, totvar_sums

__all__ = ["KINDS", "total_deviation", "total_grid", "total_variance"]

KINDS = ("totdev", "mtotdev", "ttotdev", "htotdev", "theo1", "theobr", "theoh")
_NOTES = {
    "totdev": "TOTDEV (SP 1065 eq. 25, reflected phase); EDF SP 1065 Table 7 (alpha 0..-2), "
              "Table 5 (alpha 2, 1); noise type: lag-1 ACF (oadev rules)",
    "mtotdev": "MTOTDEV (SP 1065 eq. 27); EDF as Stable32 1.60 (MDEV EDF for m < 10, "
               "else b T/tau - c); noise type: lag-1 ACF (mdev rules), B1 and R(n) below "
               "30 cluster means",
    "htotdev": "HTOTDEV (SP 1065 sec. 5.2.14, detrended and reflected rate; OHDEV at m = 1); "
               "noise type: lag-1 ACF (ohdev rules), B1 and R(n) below 30 cluster means",
    "theo1": "Theo1 (SP 1065 eq. 30), tau = 0.75 m tau0; EDF: SP 1065 Theo1 fits; noise "
             "type: lag-1 ACF at m' = round(0.75 m)",
}


def total_variance(y, ms, kind: str) -> tuple[np.ndarray, np.ndarray]:
    """``(var, count)`` of ``kind`` (totdev, mtotdev, theo1) at averaging factors ``ms``;
    the variance is in the unit of ``y`` squared (module doc; ``y`` 1-D and finite)."""
    if kind == "theo1":
        return theo1_variance(y, ms)
    y = np.ascontiguousarray(y, dtype=np.float64)
    ms = np.asarray(ms, dtype=np.int64).reshape(-1)
    if kind not in ("totdev", "mtotdev", "htotdev") or y.ndim != 1:
        raise FogbayesError(f"total_variance takes 1-D data and totdev, mtotdev or theo1, got "
                            f"'{kind}' and shape {y.shape}", fix="pass one sensor as (n,)")
    N = y.size + 1
    limit = total_limits(y.size, kind)[0]
    if ms.size == 0 or ms.min() < 1 or ms.max() > limit:
        raise TooShortError(f"{kind} needs averaging factors in 1..{limit} for {y.size} "
                            f"samples, got {ms.tolist()}", argument="taus",
                            fix="pass smaller cluster sizes (samples, not s)")
    sums = np.zeros(ms.size)
    m = ms.astype(float)
    if kind == "htotdev":
        return _htotvar(y, ms)
    S = phase_samples(y, float(np.mean(y)))
    if kind == "totdev":
        totvar_sums(S, ms, sums)
        count = np.full(ms.size, N - 2.0)
        return sums / (2.0 * m * m * count), count
    hi, lo = prefix2(S)  # mtotdev
    mtotvar_sums(S, hi, lo, ms, sums)
    count = N - 3.0 * m + 1.0
    return sums / (12.0 * m**5 * count), count


def _htotvar(y, ms):
    """HTOTVAR (module doc): MTOTDEV's compiled sums over the rate as the sequence (the
    Hadamard difference of m-point means is MTOTDEV's second difference of m-point sums
    over m); m = 1 is the overlapping Hadamard variance."""
    Y = np.ascontiguousarray(y - np.mean(y))
    hi, lo = prefix2(Y)
    sums = np.zeros(ms.size)
    mtotvar_sums(Y, hi, lo, ms, sums)
    m = ms.astype(float)
    count = Y.size - 3.0 * m + 1.0
    var = sums / (36.0 * m**3 * count)
    if (ms == 1).any():
        d = Y[2:] - 2 * Y[1:-1] + Y[:-2]
        var[ms == 1] = np.mean(d * d) / 6.0
    return var, count


def total_deviation(y, fs: float, *, taus="octave", kind: str = "totdev", ci: float = 0.9,
                    m_max: int | None = None, per_decade: int = 20,
                    bias_corrected: bool = False):
    """TOTDEV, MTOTDEV, TTOTDEV, HTOTDEV or Theo1 of rate samples ``y`` with chi-square intervals.

    Args:
        y: rate samples (shape (n,), or (batch, n) computed row by row), any unit; no NaN.
        fs: sample rate in Hz.
        taus: ``octave``, ``decade``, ``dense``, ``all`` or explicit averaging factors ``m``
            (Theo1: even, tau = 0.75 m / fs).
        kind: ``totdev``, ``mtotdev``, ``ttotdev``, ``htotdev`` or ``theo1`` (module doc).
        ci: two-sided confidence of ``dev_low``/``dev_high`` (0.683 for Stable32's 1 sigma).
        m_max: largest averaging factor of a named grid.
        per_decade: points per decade of the ``dense`` grid.
        bias_corrected: multiply the variance (and its interval) by AVAR / E[estimator] for
            the identified noise type: Theo1 (:func:`~fogbayes.stats.edf_total.theo1_bias_ratio`)
            TOTDEV (flicker and random-walk FM,
            :func:`~fogbayes.stats.edf_total.totvar_bias_ratio`) and HTOTDEV (Hvar /
            E[Htotvar], Stable32's factors,
            :func:`~fogbayes.stats.edf_total.htotvar_bias_ratio`); no correction exists
            here for MTOTDEV/TTOTDEV (refused).

    Returns:
        :class:`~fogbayes.stats.allan_result.AllanDeviation` (``excluded`` zeros, ``n_missing`` 0).

    Example:
        >>> y = np.random.default_rng(0).normal(size=4096)    # white FM, 1 Hz
        >>> r = total_deviation(y, 1.0, kind="totdev")
        >>> r.m[:3].tolist(), bool(abs(r.dev[0] - 1) < 0.05), int(r.n_terms[0])
        ([1, 2, 4], True, 4095)
        >>> r = total_deviation(y, 1.0, kind="theo1", taus=[8, 16])
        >>> r.tau.tolist()
        [6.0, 12.0]
    """
    if kind not in KINDS:
        raise FogbayesError(f"unknown total deviation '{kind}'", fix=f"use one of {', '.join(KINDS)}")
    if kind == "ttotdev":  # TTOT var = tau^2 MTOT var / 3: the modified total variance, rescaled
        if bias_corrected:
            raise FogbayesError("no bias correction is implemented for ttotdev",
                                fix="pass bias_corrected=False")
        r = total_deviation(y, fs, taus=taus, kind="mtotdev", ci=ci, m_max=m_max,
                            per_decade=per_decade)
        f = r.tau / math.sqrt(3.0)
        return r._replace(kind="ttotdev", var=r.var * f**2, dev=r.dev * f,
                          dev_low=r.dev_low * f, dev_high=r.dev_high * f,
                          note=r.note.replace("MTOTDEV (", "TTOTDEV = tau MTOTDEV / sqrt 3 (", 1))
    if bias_corrected and kind == "mtotdev":
        raise FogbayesError("no bias correction is implemented for mtotdev",
                            fix="pass bias_corrected=False")
    y = np.asarray(y, dtype=float)
    if y.ndim not in (1, 2):
        raise FogbayesError(f"rate data must be 1-D (or 2-D for a batch), got shape {y.shape}",
                            fix="pass one sensor as (n,) or a batch as (sensors, n)")
    if not (np.isfinite(fs) and fs > 0):
        raise FogbayesError(f"sample rate must be positive and finite, got {fs}",
                            fix="pass fs in Hz")
    if not np.isfinite(y).all():
        bad = int((~np.isfinite(y)).sum())
        raise FogbayesError(
            f"{kind} cannot handle missing or non-finite samples ({bad} NaN/inf): its "
            "reflected extension of the phase is undefined across a gap",
            fix="fill the gaps (e.g. interpolate), analyse the longest gap-free stretch, or "
                "use kind='oadev'/'mdev', which exclude only the terms touching a gap")
    n = y.shape[-1]
    if n < 4:
        raise TooShortError(f"{kind} needs at least 4 samples, got {n}", fix="record longer")
    if kind in ("theobr", "theoh"):  # one bias factor per record: fogbayes.stats.theoh
        if bias_corrected:
            raise FogbayesError(f"{kind} is already bias-removed (Theo1 x AVAR/Theo1)",
                                argument="bias_corrected", fix="leave bias_corrected out")
        from .theoh import theo_family

        return theo_family(y, fs, taus, kind, ci=ci, m_max=m_max, per_decade=per_decade)
    ms = total_grid(n, taus, kind, m_max=m_max, per_decade=per_decade)
    rows = [_one(row, ms, kind, n, ci, bias_corrected) for row in (y if y.ndim == 2 else [y])]
    pick = (lambda k: np.stack([r[k] for r in rows])) if y.ndim == 2 else (lambda k: rows[0][k])
    var, count, alpha, edf, lo, hi = (pick(k) for k in range(6))
    m = np.asarray(ms)
    tau = (0.75 * m if kind == "theo1" else m.astype(float)) / fs
    note = _NOTES[kind] + ("; bias-corrected to AVAR for the identified noise type"
                           if bias_corrected else "") + "; no gaps"
    return AllanDeviation(kind, float(fs), tau, m, var, np.sqrt(var), count,
                          np.zeros_like(count), alpha, edf, np.sqrt(lo), np.sqrt(hi), float(ci),
                          int(n), 0, note)


def _one(y, ms, kind, n, ci, bias_corrected):
    var, count = total_variance(y, ms, kind)
    if kind == "theo1":
        alpha = identify_alphas(y, [max(1, round(0.75 * m)) for m in ms], kind="oadev")
    else:
        rules = {"totdev": "oadev", "htotdev": "ohdev"}.get(kind, "mdev")
        alpha = identify_alphas(y, ms, kind=rules)
        if kind in ("mtotdev", "htotdev"):  # < 30 cluster means: B1 and R(n), as Stable32
            lo = -4 if kind == "htotdev" else -2
            b1 = [b1_rn_alpha(y, m, lo=lo) if 3 <= n // m < MIN_POINTS else None for m in ms]
            alpha = np.array([a if b is None else b for a, b in zip(alpha, b1)], dtype=int)
    edf = edf_for_total_kind(alpha, ms, n, kind)
    if bias_corrected:
        ratio = {"theo1": lambda: theo1_bias_ratio(alpha, ms),
                 "htotdev": lambda: htotvar_bias_ratio(alpha, ms)}.get(
                     kind, lambda: totvar_bias_ratio(alpha, ms, n))
        var = var * ratio()
    lo, hi = chi2_interval(var, edf, ci)
    return var, count, alpha, edf, lo, hi
