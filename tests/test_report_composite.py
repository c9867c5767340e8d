"""The composite (paper 000) report: raw coefficients with intervals, and the ppm verdict
with the interval of each median (issue 55)."""

from __future__ import annotations

import html as H
import re

import numpy as np
import pytest


def test_median_interval_is_the_binomial_order_statistic_interval():
    """Against scipy's binomial: [x_(k), x_(n+1-k)] with the largest k whose coverage
    1 - 2 P(Bin(n, 1/2) <= k - 1) is at least 90 %; and its coverage on lognormal draws
    (true median 1) is at least 90 % (Monte Carlo, 4000 sets: s.e. 0.5 %)."""
    from scipy.stats import binom

    from fogbayes.render.composite import median_interval

    rng = np.random.default_rng(3)
    for n in (5, 12, 140):
        x = rng.lognormal(size=n)
        k = max(k for k in range(1, n // 2 + 1) if 1 - 2 * binom.cdf(k - 1, n, 0.5) >= 0.9)
        s = np.sort(x)
        med, lo, hi = median_interval(x)
        assert med == pytest.approx(np.median(x))
        assert (lo, hi) == (s[k - 1], s[n - k])
    hits = 0
    for _ in range(4000):
        _, lo, hi = median_interval(rng.lognormal(size=60))
        hits += lo <= 1.0 <= hi
    assert 0.9 - 0.015 <= hits / 4000 <= 0.97  # exact coverage 0.9476 for n = 60


@pytest.fixture(scope="module")
def composite_report(tmp_path_factory):
    from fogbayes.simulate import simulate
    from fogbayes.workflow.api import fit
    from fogbayes.workflow.report import build_report

    rec = simulate("paper000", seed=1).recording
    doc = fit(rec, model="composite", orders="2,3,2,2")
    out = build_report(rec, tmp_path_factory.mktemp("comp") / "r.html", fit=doc, allan=False)
    return doc, out.read_text()


def _num(s: str) -> float:
    s = s.replace("−", "-")
    m = re.fullmatch(r"(-?[\d.]+)×10([⁻⁰¹²³⁴⁵⁶⁷⁸⁹]+)", s)
    if m:
        exp = m.group(2).translate(str.maketrans("⁻⁰¹²³⁴⁵⁶⁷⁸⁹", "-0123456789"))
        return float(m.group(1)) * 10.0 ** int(exp)
    return float(s)


def test_composite_report_has_a_coefficient_table_with_intervals(composite_report):
    """One row per raw coefficient (params.labels), its value inside its 90 % interval,
    the interval's ends those of the document, to the digits shown."""
    doc, page = composite_report
    rows = re.findall(r"<tr>(.*?)</tr>", page, flags=re.S)
    table = {}
    for r in rows:
        cells = [H.unescape(re.sub(r"<.*?>", "", c)).strip()
                 for c in re.findall(r"<t[dh][^>]*>(.*?)</t[dh]>", r, flags=re.S)]
        if cells and re.fullmatch(r"[Mcd]\[\d(,\d)?\]", cells[0]):
            table[cells[0]] = cells
    labels = doc["params"]["labels"]
    assert sorted(table) == sorted(labels)
    flat = {k: np.ravel(np.asarray(doc["params"][k]["M"], float)).tolist()
            + list(doc["params"][k]["c"]) + list(doc["params"][k]["d"])
            for k in ("raw", "raw_lo90", "raw_hi90")}
    for n, lab in enumerate(labels):
        cells = table[lab]
        value = _num(cells[2])
        lo, hi = (_num(x.strip()) for x in cells[4].strip("[]").split(","))
        assert lo <= value <= hi, (lab, cells)
        assert lo == pytest.approx(flat["raw_lo90"][n], rel=1e-3)
        assert hi == pytest.approx(flat["raw_hi90"][n], rel=1e-3)
        assert lo < hi  # shown with enough digits to tell the ends apart
    assert "V per °C·(°/s)" in page  # M[1,0]: output unit per °C per °/s


def test_composite_verdict_gives_each_median_its_interval(composite_report):
    """The ppm verdict: median [low, high] before -> after, each interval around its
    median and equal to the order-statistic interval of the cells' |error| in ppm."""
    from fogbayes.render.composite import median_interval

    doc, page = composite_report
    verdict = H.unescape(re.search(r"Verdict:</b>(.*?)</p>", page, flags=re.S).group(1))
    m = re.search(r"median (\S+) \[(\S+), (\S+)\] → (\S+) \[(\S+), (\S+)\] ppm", verdict)
    assert m, verdict
    b_med, b_lo, b_hi, a_med, a_lo, a_hi = (_num(x) for x in m.groups())
    assert b_lo <= b_med <= b_hi and a_lo <= a_med <= a_hi
    after = [1e4 * abs(r["fogbayes_error_pct"]) for r in doc["table"]]
    med, lo, hi = median_interval(after)
    assert (a_med, a_lo, a_hi) == pytest.approx((med, lo, hi), rel=5e-3)  # 3 digits shown
    assert a_hi < b_lo  # the compensation's gain on paper 000's table is beyond doubt
