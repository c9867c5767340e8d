"""TheoBR and TheoH (kind="theobr", "theoh") against Stable32's PHASE.DAT tables and closed forms.

References (../shared/data/reference/stable32_phasedat, SOURCE.md there; rate input
``diff(PHASE.DAT)`` at fs = 1 Hz):

* ``phase_dat_theo1.txt`` (Stable32 1.60, header "Alpha = 1") is TheoBR: every printed value is
  the raw Theo1 (``phase_dat_theo1_alpha0.txt``) times one factor, 0.602787 in variance
  (bounds from the printed digits: 0.6027864 ... 0.6027871), which is the mean AVAR/Theo1 over
  m = 9 + 3i / 12 + 4i, i = 0 ... floor(N/6 - 3) (measured 0.6027870); its alpha 1 is the
  noise type of that factor. Stable32 prints no interval in this table.
* TheoH: the PHASE.DAT folder has no TheoH table. Its rows are checked against the tables it
  is made of: OADEV (``phase_dat_oadev_octave.txt``, values and 68.3 % bounds) below
  m_k = 0.2 n = 200 and TheoBR (``phase_dat_theo1.txt``) from there on.
* Closed forms (simulation): for white PM, E[AVAR]/E[Theo1] = 0.09 + 0.74 / tau^0.4 (SP 1065,
  Howe & Tasset), so k_f, a mean of ratios, is near the mean of that curve over its taus.
"""

from __future__ import annotations

import numpy as np
import pytest
from test_stable32_phasedat_totals import _rate, _table

from fogbayes.errors import FogbayesError
from fogbayes.stats.allan import allan_deviation
from fogbayes.stats.edf import chi2_interval
from fogbayes.stats.edf_total import edf_theo1
from fogbayes.stats.theo1 import theo1_variance
from fogbayes.stats.theoh import _ratio_count, theobr_alpha, theobr_factor, theoh_switch


def _digits(v) -> list[str]:
    return [f"{x:.4e}" for x in v]


def test_theobr_is_stable32s_theo1_table_to_the_printed_digits():
    t = _table("phase_dat_theo1.txt")
    ms = t[:, 0].astype(int)
    r = allan_deviation(_rate(), 1.0, taus=ms, kind="theobr", ci=0.683)
    assert _digits(r.dev) == _digits(t[:, 5])  # all 181 rows, m = 10 ... 998
    np.testing.assert_allclose(r.tau, t[:, 1])
    assert (r.alpha == t[:, 3]).all()  # Stable32's "Alpha = 1"
    assert abs(theobr_factor(_rate()) - 0.602787) < 1e-6


def test_the_factor_is_not_sp1065s_fixed_alpha_curve():
    """The same table is not Theo1 x (a + b / tau^c) for alpha = 1 (SP 1065's per-noise bias):
    that changes with tau, the printed ratio does not (measured spread of the printed ratio
    1.6e-4, rounding of the printed digits; of the curve 0.34 over m = 10 ... 998)."""
    t, raw = _table("phase_dat_theo1.txt"), _table("phase_dat_theo1_alpha0.txt")
    ratio = (t[:, 5] / raw[:, 5]) ** 2
    assert np.ptp(ratio) < 2e-4
    curve = 0.14 + 0.82 / (0.75 * t[:, 0]) ** 0.3
    assert np.ptp(curve) > 0.1


def test_theoh_is_oadev_then_theobr():
    y = _rate()
    assert theoh_switch(y.size) == 200
    oadev = _table("phase_dat_oadev_octave.txt")  # m = 1 ... 256
    theo = _table("phase_dat_theo1.txt")
    low = oadev[oadev[:, 0] < 200]
    high = theo[np.isin(theo[:, 0], [200, 250, 400, 510, 750, 998])]
    ms = np.concatenate([low[:, 0], high[:, 0]]).astype(int)
    r = allan_deviation(y, 1.0, taus=ms, kind="theoh", ci=0.683)
    k = len(low)
    assert r.m.tolist() == ms.tolist() and r.kind == "theoh"
    np.testing.assert_allclose(r.tau, np.concatenate([low[:, 1], 0.75 * high[:, 0]]))
    assert _digits(r.dev) == _digits(np.concatenate([low[:, 5], high[:, 5]]))
    # the Allan rows' 68.3 % bounds are Stable32's OADEV bounds (measured <= 3.7e-4)
    np.testing.assert_allclose(r.dev_low[:k], low[:, 4], rtol=1e-2)
    np.testing.assert_allclose(r.dev_high[:k], low[:, 6], rtol=1e-2)
    # TheoBR rows: the white-FM Theo1 EDF on the TheoBR variance
    edf = np.array([edf_theo1(0, int(m), y.size + 1) for m in high[:, 0]])
    lo, hi = chi2_interval(r.var[k:], edf, 0.683)
    np.testing.assert_allclose(r.dev_low[k:], np.sqrt(lo), rtol=1e-12)
    np.testing.assert_allclose(r.dev_high[k:], np.sqrt(hi), rtol=1e-12)
    assert "TheoH" in r.note and "0.602787" in r.note


def test_named_grids():
    y = _rate()
    r = allan_deviation(y, 1.0, taus="octave", kind="theoh")
    assert r.m.tolist() == [1, 2, 4, 8, 16, 32, 64, 128, 256, 512]
    assert r.tau.tolist() == [1, 2, 4, 8, 16, 32, 64, 128, 192, 384]
    r = allan_deviation(y, 1.0, taus="decade", kind="theoh")
    assert r.m.tolist() == [1, 2, 4, 10, 20, 40, 100, 200, 400, 1000]
    r = allan_deviation(y, 1.0, taus="octave", kind="theobr")
    assert r.m.tolist()[:2] == [2, 4] and r.tau[0] == 1.5


def test_white_pm_factor_follows_the_bias_curve():
    """White PM: Theo1 under-reads AVAR by a + b / tau^c; k_f averages the ratios, so it lies
    near the mean of that curve over tau = 0.75 (12 + 4i) (measured 0.156-0.162 against 0.154
    for 4 seeds, N = 3001); white FM: near 1 (the single-seed scatter is large, k_f leans on
    long-tau Allan terms; measured 0.98-1.32)."""
    N = 3001
    tau = 0.75 * (12 + 4 * np.arange(_ratio_count(N) + 1))
    expect = np.mean(0.09 + 0.74 / tau**0.4)
    for seed in range(2):
        rng = np.random.default_rng(seed)
        k = theobr_factor(np.diff(rng.normal(size=N)))
        assert abs(k / expect - 1) < 0.1
        assert theobr_alpha(k) == 2  # nearest nominal: 0.4 (white PM)


def test_factor_is_mean_of_ratios_and_fast_path_for_fm():
    rng = np.random.default_rng(3)
    y = np.cumsum(rng.normal(size=3000)) * 0.01 + rng.normal(size=3000)  # white + RW FM
    N = y.size + 1
    n = _ratio_count(N)
    x = np.concatenate([[0.0], np.cumsum(y - y.mean())])
    av = [np.sum((x[2 * m:] - 2 * x[m:-m] + x[:-2 * m]) ** 2) / (2 * m * m * (N - 2 * m))
          for m in 9 + 3 * np.arange(n + 1)]
    th = theo1_variance(y, 12 + 4 * np.arange(n + 1))[0]
    exact = theobr_factor(y)
    assert exact == pytest.approx(np.mean(np.array(av) / th), rel=1e-12)
    # Taylor & Howe's block-averaged factor on FM noise (measured 1.3 % off here)
    assert theobr_factor(y, exact_max=1000) == pytest.approx(exact, rel=0.03)


def test_refusals():
    y = _rate()
    with pytest.raises(FogbayesError, match="already bias-removed"):
        allan_deviation(y, 1.0, kind="theoh", bias_corrected=True)
    with pytest.raises(FogbayesError, match="even"):
        allan_deviation(y, 1.0, kind="theoh", taus=[1, 2, 301])
    with pytest.raises(FogbayesError, match="18 rate samples"):
        theobr_factor(np.ones(17))


def test_cli_kind_theoh(tmp_path, capsys):
    """`fogbayes allan --kind theoh`: the document carries TheoH equal to allan_deviation on
    the same rate (90 % intervals)."""
    import json

    from fogbayes.cli import main
    from fogbayes.data import load

    y = np.random.default_rng(5).normal(size=1200)
    path = tmp_path / "r.csv"
    path.write_text("time,output\n" + "".join(f"{t:.1f},{v:.17g}\n" for t, v in enumerate(y)))
    assert main(["allan", str(path), "--json", "-", "--kind", "theoh"]) == 0
    cap = capsys.readouterr()
    d = json.loads(cap.out)["deviation"]
    assert d["kind"] == "theoh"
    ref = allan_deviation(np.asarray(load(path).rate("deg/h")), 1.0, kind="theoh", ci=0.9)
    np.testing.assert_allclose(d["dev"], ref.dev, rtol=1e-12)
    np.testing.assert_allclose(d["tau"], ref.tau, rtol=1e-12)
    assert main(["allan", str(path), "--json", str(tmp_path / "x.json"), "--kind", "theoh",
                 "--bias-corrected"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "--bias-corrected" in err
