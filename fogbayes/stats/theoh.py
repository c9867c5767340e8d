r"""TheoBR (bias-removed Theo1) and TheoH (Allan / TheoBR hybrid), as Stable32 1.60 computes them.

Rate samples :math:`y_0 \dots y_{n-1}` at ``fs`` (``tau0 = 1/fs``), phase ``N = n + 1`` points.

**TheoBR** (Howe & Tasset 2004; Taylor & Howe 2010; NIST SP 1065 sec. 5.2.15): Theo1
(:mod:`~fogbayes.stats.theo1`, even ``m``, ``tau = 0.75 m tau0``) times one factor for the
whole run, the mean ratio of the overlapping Allan variance to Theo1 at the same averaging
time,

.. math:: k_f = \frac{1}{n_r + 1} \sum_{i=0}^{n_r}
    \frac{\mathrm{AVAR}(m = 9 + 3i)}{\mathrm{Theo1}(m = 12 + 4i)}, \qquad
    n_r = \lfloor N/6 - 3 \rfloor

(``n_r`` as Stable32 1.60 prints it; W. J. Riley's R TheoBR uses ``0.1 N / 3 - 3``; where ``N``
is a multiple of 6 the last Allan term would be empty and that ratio is left out). No noise type is assumed: the factor removes Theo1's
bias for whatever mixture the record holds. Stable32 prints this as its Theo1 table with an
"Alpha" header; that alpha is the noise type whose nominal Theo1 bias (AVAR/Theo1 = 0.4,
0.6, 1, 1.71, 2.24 for alpha = 2 ... -2, Howe & Tasset 2003) lies nearest ``k_f`` on a log
scale (:func:`theobr_alpha`).

The ratios cost O(N^3) (Theo1 sums to m = 2N/3). Above :data:`EXACT_MAX` phase points ``k_f``
is Taylor & Howe's fast TheoBR: the same mean on the phase averaged in blocks of
``b = ceil(N / EXACT_MAX)`` points, plus ``0.00055 (b - 1)``. The block average is a low-pass
on the phase, so this holds for FM noise; where white or flicker PM dominates the ratios
near m = 12 it overstates ``k_f`` (simulated white PM, b = 4: +25 %).

**TheoH** (Howe, Taylor & Tasset 2006; SP 1065): per averaging factor ``m`` of the grid,
the overlapping Allan deviation at ``tau = m tau0`` for ``m < m_k`` and TheoBR at
``tau = 0.75 m tau0`` for even ``m >= m_k``, with ``m_k = floor(0.2 n)`` (20 % of the
record, where Stable32 1.60's TheoH table turns to Theo1). The taus are not
monotonic at the switch (Allan reaches 0.2 T, TheoBR starts at 0.15 T), as in Stable32's
table. Allan rows: noise type and EDF as
:func:`~fogbayes.stats.allan.allan_deviation` (``oadev``). TheoBR rows (and ``theobr``):
``alpha`` is :func:`theobr_alpha`; the EDF is the white-FM Theo1 fit
(:func:`~fogbayes.stats.edf_total.edf_theo1` at alpha 0) whatever the noise, the EDF that
Stable32's printed TheoH bounds invert to.

Example:
    >>> import numpy as np
    >>> y = np.random.default_rng(0).normal(size=2000)          # white FM: k_f ~ 1
    >>> bool(0.8 < theobr_factor(y) < 1.25), theobr_alpha(1.0), theobr_alpha(0.6028)
    (True, 0, 1)
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import TooShortError
from .allan_result import AllanDeviation
from .allan_blocked import allan_variance_fast
from .edf import chi2_interval, edf_for_kind
from .edf_total import edf_theo1
from .noise_id import identify_alphas
from .theo1 import theo1_limit, theo1_variance
from .total_taus import total_grid

__all__ = ["EXACT_MAX", "theobr_factor", "theobr_alpha", "theoh_switch", "theobr_deviation",
           "theoh_deviation"]

#: nominal AVAR/Theo1 per noise type alpha (Howe & Tasset 2003), for naming k_f's noise type
NOMINAL_THEO1_BIAS = {2: 0.4, 1: 0.6, 0: 1.0, -1: 1.71, -2: 2.24}
#: largest phase record whose TheoBR factor is computed from all its ratios directly
EXACT_MAX = 8000
#: Taylor & Howe's increment of the block-averaged factor per extra averaged point
FAST_SLOPE = 0.00055


def _ratio_count(N: int) -> int:
    """``n_r`` (module doc) for ``N`` phase points; -1 when no ratio exists."""
    n = math.floor(N / 6 - 3)
    while n >= 0 and N - 2 * (9 + 3 * n) < 1:  # the last Allan term must hold a difference
        n -= 1
    return n


def _exact_factor(y: np.ndarray) -> float:
    N = y.size + 1
    n = _ratio_count(N)
    if n < 0:
        raise TooShortError(f"TheoBR needs at least 18 rate samples (19 phase points), got {N - 1}",
                            argument="taus", fix="record longer or use kind='theo1'")
    x = np.concatenate([[0.0], np.cumsum(y - np.mean(y))])  # phase in units of y * tau0
    ma = 9 + 3 * np.arange(n + 1)
    avar = np.array([np.mean((x[2 * m:] - 2 * x[m:-m] + x[:-2 * m]) ** 2) / (2.0 * m * m)
                     for m in ma])
    theo, _ = theo1_variance(y, 12 + 4 * np.arange(n + 1))
    return float(np.mean(avar / theo))


def theobr_factor(y, *, exact_max: int = EXACT_MAX) -> float:
    """``k_f`` = mean AVAR / Theo1 (module doc) of rate samples ``y`` (1-D, finite)."""
    y = np.ascontiguousarray(y, dtype=np.float64)
    N = y.size + 1
    if N <= exact_max:
        return _exact_factor(y)
    b = math.ceil(N / exact_max)
    x = np.concatenate([[0.0], np.cumsum(y - np.mean(y))])
    xb = x[: (N // b) * b].reshape(-1, b).mean(axis=1)  # phase averaged in blocks of b
    return _exact_factor(np.diff(xb)) + FAST_SLOPE * (b - 1)


def theobr_alpha(kf: float) -> int:
    """Noise type whose nominal AVAR/Theo1 is nearest ``kf`` in log (geometric-mean bounds)."""
    return min(NOMINAL_THEO1_BIAS, key=lambda a: abs(math.log(kf / NOMINAL_THEO1_BIAS[a])))


def theoh_switch(n: int) -> int:
    """First averaging factor of TheoH's TheoBR part for ``n`` rate samples: floor(0.2 n)."""
    return math.floor(0.2 * n)


def _theobr_rows(y, ms, ci):
    kf = theobr_factor(y)
    var, count = theo1_variance(y, ms)
    var = var * kf
    N = y.size + 1
    alpha = np.full(len(ms), theobr_alpha(kf))
    edf = np.array([edf_theo1(0, int(m), N) for m in ms])
    lo, hi = chi2_interval(var, edf, ci)
    return kf, var, count, alpha, edf, lo, hi


def _record(kind, fs, tau, m, var, count, alpha, edf, lo, hi, ci, n, note):
    count = np.asarray(count, dtype=float)
    return AllanDeviation(kind, float(fs), np.asarray(tau, dtype=float), np.asarray(m), var,
                          np.sqrt(var), count, np.zeros_like(count), np.asarray(alpha), edf,
                          np.sqrt(lo), np.sqrt(hi), float(ci), int(n), 0, note)


def theobr_deviation(y, fs: float, ms, *, ci: float) -> AllanDeviation:
    """TheoBR at even averaging factors ``ms`` (``tau = 0.75 m / fs``) of 1-D finite ``y``."""
    y = np.ascontiguousarray(y, dtype=np.float64)
    ms = np.asarray(ms, dtype=np.int64)
    kf, var, count, alpha, edf, lo, hi = _theobr_rows(y, ms, ci)
    note = (f"TheoBR: Theo1 (SP 1065 eq. 30) x k_f = {kf:.6g}, the mean AVAR/Theo1 over "
            f"m = 9 + 3i / 12 + 4i (Stable32); tau = 0.75 m tau0; noise type named from k_f; "
            "EDF: the white-FM Theo1 fit (as Stable32); no gaps")
    return _record("theobr", fs, 0.75 * ms / fs, ms, var, count, alpha, edf, lo, hi, ci,
                   y.size, note)


def theoh_grid(ms, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Split averaging factors into TheoH's Allan part (m < m_k) and TheoBR part (the even
    m >= m_k up to the Theo1 limit); raises where an m of the TheoBR part is odd."""
    ms = np.asarray(ms, dtype=np.int64)
    mk = theoh_switch(n)
    allan = ms[ms < mk]
    theo = ms[ms >= mk]
    if (theo % 2).any() or (theo > theo1_limit(n)).any():
        raise TooShortError(f"TheoH's TheoBR part (m >= {mk}) needs even m <= "
                            f"{theo1_limit(n)}, got {theo.tolist()}", argument="taus",
                            fix="pass even cluster sizes from m = 0.2 n on")
    return allan, theo


def _oadev_rows(y, fs: float, ms: tuple[int, ...], ci: float) -> tuple:
    """OADEV rows of a gap-free record as :func:`fogbayes.stats.allan.allan_deviation` gives
    them: variances, lag-1 ACF noise type, Greenhall EDF and chi-square bounds."""
    var, count = allan_variance_fast(y, ms)
    alpha = identify_alphas(y, ms, kind="oadev")
    edf = edf_for_kind(alpha, ms, y.size, "oadev")
    lo, hi = chi2_interval(var, edf, ci)
    return np.asarray(ms) / fs, np.asarray(ms), var, count, alpha, edf, lo, hi


def theoh_deviation(y, fs: float, allan_ms, theo_ms, *, ci: float) -> AllanDeviation:
    """TheoH rows: OADEV at ``allan_ms`` then TheoBR at ``theo_ms`` (module doc)."""
    y = np.ascontiguousarray(y, dtype=np.float64)
    parts = []
    if len(allan_ms):
        parts.append(_oadev_rows(y, fs, tuple(int(m) for m in allan_ms), ci))
    kf = None
    if len(theo_ms):
        theo_ms = np.asarray(theo_ms, dtype=np.int64)
        kf, var, count, alpha, edf, lo, hi = _theobr_rows(y, theo_ms, ci)
        parts.append((0.75 * theo_ms / fs, theo_ms, var, count, alpha, edf, lo, hi))
    cols = [np.concatenate([np.asarray(p[k], dtype=float) for p in parts]) for k in range(8)]
    tau, m, var, count, alpha, edf, lo, hi = cols
    note = (f"TheoH: OADEV for m < {theoh_switch(y.size)} (20 % of the record), TheoBR "
            "(Theo1 x k_f" + (f" = {kf:.6g}" if kf is not None else "") +
            ", tau = 0.75 m tau0) from there on (Stable32); no gaps")
    return _record("theoh", fs, tau, m.astype(np.int64), var, count, alpha.astype(int), edf,
                   lo, hi, ci, y.size, note)


def theo_family(y, fs: float, taus, kind: str, *, ci: float, m_max: int | None,
                per_decade: int) -> AllanDeviation:
    """``theobr`` or ``theoh`` of finite rate data ``y`` ((n,) or (batch, n), row by row) on a
    named grid or explicit averaging factors (``theobr``: even m, the Theo1 grid; ``theoh``:
    the TOTDEV grid below ``m_k``, the Theo1 grid from ``m_k`` on, :func:`theoh_grid`)."""
    n = y.shape[-1]
    if kind == "theobr":
        ms = np.asarray(total_grid(n, taus, "theo1", m_max=m_max, per_decade=per_decade))
        one = lambda row: theobr_deviation(row, fs, ms, ci=ci)  # noqa: E731
    else:
        if isinstance(taus, str):
            mk = theoh_switch(n)
            cap = theo1_limit(n) if m_max is None else min(int(m_max), theo1_limit(n))
            low = [m for m in total_grid(n, taus, "totdev", m_max=max(1, mk - 1),
                                         per_decade=per_decade) if m < mk]
            high = [m for m in total_grid(n, taus, "theo1", m_max=max(2, cap),
                                          per_decade=per_decade) if mk <= m <= cap]
            allan, theo = np.asarray(low, dtype=np.int64), np.asarray(high, dtype=np.int64)
        else:
            allan, theo = theoh_grid(np.unique(np.asarray(taus, dtype=np.int64)), n)
            if allan.size and allan[0] < 1:
                raise TooShortError("cluster sizes must be >= 1", argument="taus",
                                    fix="pass positive cluster sizes (samples, not s)")
        one = lambda row: theoh_deviation(row, fs, allan, theo, ci=ci)  # noqa: E731
    if y.ndim == 1:
        return one(y)
    rows = [one(row) for row in y]
    stack = {k: np.stack([getattr(r, k) for r in rows])
             for k in ("var", "dev", "n_terms", "excluded", "alpha", "edf", "dev_low",
                       "dev_high")}
    return rows[0]._replace(**stack)
