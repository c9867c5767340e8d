"""Composite (paper 000) report: raw coefficients with intervals, cell errors before -> after.

U = sum M_ij T^i W^(j+1) + sum c_i T^i + t sum d_i T^i (T °C, W °/s, t s). The median cell
error's distribution-free interval is [x_(k), x_(n+1-k)], coverage 1 - 2 P(Bin(n, 1/2) < k).
"""

from __future__ import annotations

import math

import numpy as np

from .html import Cell, Section, fmt

PPM_PER_PCT = 1e4  # % -> parts per million, the unit of rate-table errors


def median_interval(x, level: float = 0.9) -> tuple[float, float, float]:
    """(median, low, high): the distribution-free ``level`` interval of the median of the
    population ``x`` was drawn from (order statistics, see module doc); NaNs left out.

    Fewer than 5 values cannot reach 90 %: the interval is then the sample's range
    (coverage 1 - 2^(1-n)), stated as such by the caller's level."""
    v = np.sort(np.asarray(x, float)[np.isfinite(np.asarray(x, float))])
    n = v.size
    if n == 0:
        return math.nan, math.nan, math.nan
    # cdf[k] = P(Bin(n, 1/2) <= k), exactly, in log space
    logs = [math.lgamma(n + 1) - math.lgamma(j + 1) - math.lgamma(n - j + 1) - n * math.log(2)
            for j in range(n + 1)]
    cdf = np.cumsum(np.exp(logs))
    k = 1
    for cand in range(1, n // 2 + 1):  # coverage 1 - 2 P(Bin < cand) = 1 - 2 cdf[cand - 1]
        if 1.0 - 2.0 * cdf[cand - 1] >= level:
            k = cand
        else:
            break
    return float(np.median(v)), float(v[k - 1]), float(v[n - k])


def _power(e: int, unit: str) -> str:
    if e == 0:
        return ""
    sup = "".join("⁰¹²³⁴⁵⁶⁷⁸⁹"[int(ch)] for ch in str(e)) if e > 1 else ""
    return f"{unit}{sup}"


def coefficient_term(label: str, out_unit: str) -> tuple[str, str]:
    """``'M[1,2]'`` -> (``'T W³'``, ``'V per °C·(°/s)³'``): the term a raw coefficient
    multiplies, and the coefficient's unit."""
    kind, idx = label.split("[", 1)
    ij = [int(s) for s in idx.rstrip("]").split(",")]
    i = ij[0]
    factors, units = [], []
    if i:
        factors.append("T" + ("" if i == 1 else _power(i, "")))
        units.append(_power(i, "°C"))
    if kind == "M":
        j = ij[1] + 1
        factors.append("W" + ("" if j == 1 else _power(j, "")))
        units.append(f"(°/s){_power(j, '') if j > 1 else ''}")
    elif kind == "d":
        factors.insert(0, "t")
        units.insert(0, "s")
    term = " ".join(factors) or "1"
    unit = out_unit if not units else f"{out_unit} per {'·'.join(units)}"
    return term, unit


def digits(low: float, high: float) -> int:
    """Significant digits that tell ``low`` from ``high`` apart (at least 4): a tight
    interval around 39.62 needs seven."""
    width, size = abs(high - low), max(abs(low), abs(high))
    if not (np.isfinite(width) and width > 0 and size > 0):
        return 4
    return max(4, min(12, math.ceil(math.log10(size / width)) + 2))


def interval_text(low: float, high: float) -> str:
    """``[low, high]`` with :func:`digits` significant digits."""
    sig = digits(low, high)
    return f"[{fmt(low, sig=sig)}, {fmt(high, sig=sig)}]"


_ROLE = {"M": "scale factor S1(T) S2(W)", "c": "bias U0(T)", "d": "drift U1(T) t"}


def coefficient_table(sec: Section, doc: dict) -> bool:
    """Add the composite's raw coefficients with standard deviation and 90 % interval
    (and the posterior's when the fit has one) to ``sec``; False when the document has none."""
    p = doc.get("params") or {}
    raw, labels = p.get("raw"), p.get("labels")
    if not isinstance(raw, dict) or not labels or "raw_lo90" not in p:
        return False
    out_unit = (doc.get("input") or {}).get("unit") or "U"

    def flat(d):
        return [float(x) for k in ("M", "c", "d")
                for x in np.ravel(np.asarray(d.get(k, []), float))]

    vals, sd, lo, hi = (flat(p[k]) for k in ("raw", "raw_sd", "raw_lo90", "raw_hi90"))
    bayes = doc.get("bayes") or {}
    have_post = all(k in bayes for k in ("raw_mean", "raw_lo90", "raw_hi90"))
    if have_post:
        pm, plo, phi = (flat(bayes[k]) for k in ("raw_mean", "raw_lo90", "raw_hi90"))
    rows = []
    for n, lab in enumerate(labels):
        term, unit = coefficient_term(lab, out_unit)
        row = [Cell(lab, title=f"{_ROLE[lab[0]]}; JSON: params.raw"), term,
               Cell(fmt(vals[n], sig=digits(lo[n], hi[n]))), sd[n],
               Cell(interval_text(lo[n], hi[n])), unit]
        if have_post:
            row[5:5] = [pm[n], Cell(interval_text(plo[n], phi[n]))]
        rows.append(row)
    header = ["coefficient", "multiplies", "value", "std. dev.", "90 % interval", "unit"]
    if have_post:
        header[5:5] = ["posterior mean", "posterior 90 %"]
    sec.table(header, rows, caption=(
        f"raw coefficients of U = Σ M_ij T^i W^(j+1) + Σ c_i T^i + t Σ d_i T^i (paper 000; "
        f"U in {out_unit}, T in °C, W in °/s, t in s), orders "
        f"{doc.get('orders', {}).get('label', '')}; "
        "intervals from the fit's covariance under its noise model"))
    return True


def error_verdict(table: list[dict], level: float = 0.9) -> tuple[str, bool | None]:
    """The headline sentence on the cells' relative rate error, before -> after, with the
    ``level`` interval of each median (:func:`median_interval`), and whether the median fell."""
    b = PPM_PER_PCT * np.array([abs(r["before_error_pct"]) for r in table], float)
    a = PPM_PER_PCT * np.array([abs(r.get("fogbayes_error_pct", np.nan)) for r in table], float)
    mb, lb, hb = median_interval(b, level)
    ma, la, ha = median_interval(a, level)
    sentence = (f"relative rate error over the {len(table)} table cells, before → after "
                f"compensation: median {fmt(mb, sig=3)} [{fmt(lb, sig=3)}, {fmt(hb, sig=3)}] → "
                f"{fmt(ma, sig=3)} [{fmt(la, sig=3)}, {fmt(ha, sig=3)}] ppm ({level:.0%} "
                f"distribution-free intervals of the median over cells), largest "
                f"{fmt(np.nanmax(b), sig=3)} → {fmt(np.nanmax(a), sig=3)} ppm.")
    return sentence, bool(ma < mb)
