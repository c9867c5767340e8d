"""HTOTDEV (fogbayes.stats.total, kind="htotdev"): the definition, drift, white FM, bias option.

Stable32's printed values and intervals are checked in tests/test_stable32_phasedat_totals.py;
here the estimator against a direct transcription of its definition (NIST SP 1065 sec. 5.2.14:
half-average detrending of each 3m-sample subsequence, even reflection to 9m, Hadamard
differences of m-point means), and its properties.
"""

from __future__ import annotations

import numpy as np
import pytest

from fogbayes.errors import FogbayesError
from fogbayes.stats.allan import allan_deviation
from fogbayes.stats.edf_total import HTOTVAR_BIAS, htotvar_bias_ratio
from fogbayes.stats.total import total_deviation


def _htotvar_direct(y, m):
    """The definition, loop by loop (O(n m^2)): mean over subsequences of the mean over the
    6m Hadamard differences of the reflected, detrended subsequence, over 6."""
    y = np.asarray(y, float)
    h = (3 * m) // 2
    out = []
    for j in range(y.size - 3 * m + 1):
        seq = y[j:j + 3 * m]
        slope = (seq[-h:].mean() - seq[:h].mean()) / (3 * m - h)  # half-average slope
        x = seq - slope * np.arange(3 * m)
        ext = np.concatenate([x[::-1], x, x[::-1]])
        z = [ext[i:i + m].mean() - 2 * ext[i + m:i + 2 * m].mean() + ext[i + 2 * m:i + 3 * m].mean()
             for i in range(6 * m)]
        out.append(np.mean(np.square(z)) / 6.0)
    return float(np.mean(out))


def test_equals_the_definition():
    y = np.random.default_rng(1).normal(size=240).cumsum() * 0.1 + np.random.default_rng(2).normal(
        size=240)
    ms = [2, 3, 5, 8, 13, 40, 80]
    res = total_deviation(y, 1.0, taus=ms, kind="htotdev")
    ref = [_htotvar_direct(y, m) for m in ms]
    np.testing.assert_allclose(res.var, ref, rtol=1e-10)
    np.testing.assert_array_equal(res.n_terms, [240 - 3 * m + 1 for m in ms])


def test_m1_is_the_overlapping_hadamard_deviation():
    y = np.random.default_rng(3).normal(size=500)
    a = allan_deviation(y, 2.0, taus=[1], kind="htotdev")
    b = allan_deviation(y, 2.0, taus=[1], kind="ohdev")
    np.testing.assert_allclose(a.dev, b.dev, rtol=1e-12)


def test_a_rate_ramp_changes_nothing():
    """Each subsequence loses its own linear drift, and a Hadamard difference of a ramp is 0:
    a gyro's rate ramp leaves HTOTDEV as it was (OADEV grows with tau instead)."""
    rng = np.random.default_rng(4)
    y = rng.normal(size=3000)
    ramp = y + 2e-3 * np.arange(y.size)
    a = total_deviation(y, 1.0, kind="htotdev")
    b = total_deviation(ramp, 1.0, kind="htotdev")
    np.testing.assert_allclose(b.dev, a.dev, rtol=1e-8)
    o = allan_deviation(ramp, 1.0, kind="oadev")
    assert o.dev[-1] > 10 * a.dev[-1]


def test_white_fm_level_and_interval_coverage():
    """White FM, sigma 1: Hvar(m) = 1/m and E[Htotvar] = 0.995 / m. Over 200 records the mean
    of Htotvar m at m = 8, 32 is 0.995 to its standard error (measured 0.993 +- 0.005,
    1.002 +- 0.010), and the 90 % bias-corrected intervals cover 1/sqrt(m) 0.86-0.94 of the
    time (measured 0.913: 0.97 at m = 8, where Greenhall's OHDEV EDF is the conservative
    fallback, 0.855 at m = 32, SP 1065's HTOTDEV EDF)."""
    rng = np.random.default_rng(5)
    ms = [8, 32]
    v, hit = [], []
    for _ in range(200):
        r = total_deviation(rng.normal(size=2048), 1.0, taus=ms, kind="htotdev", ci=0.9,
                            bias_corrected=True)
        truth = 1 / np.sqrt(r.m)
        v.append(r.var * r.m * np.where(r.alpha == 0, HTOTVAR_BIAS[0], 1.0))
        hit.append((r.dev_low <= truth) & (truth <= r.dev_high))
    v = np.array(v)
    se = v.std(axis=0) / np.sqrt(len(v))
    assert np.all(np.abs(v.mean(axis=0) - 0.995) < 3 * se)
    assert 0.86 <= np.mean(hit) <= 0.94


def test_bias_correction_and_refusals():
    y = np.random.default_rng(6).normal(size=900)
    a = allan_deviation(y, 1.0, kind="htotdev", ci=0.683)
    b = allan_deviation(y, 1.0, kind="htotdev", ci=0.683, bias_corrected=True)
    np.testing.assert_allclose(b.var, a.var * htotvar_bias_ratio(a.alpha, a.m), rtol=1e-12)
    assert htotvar_bias_ratio([0, 0, 1, -2], [1, 2, 2, 2]).tolist() == pytest.approx(
        [1.0, 1 / 0.995, 1.0, 1 / 0.771])
    assert a.m[-1] == 256 and a.m[0] == 1  # octave grid up to n // 3 = 300
    with pytest.raises(FogbayesError, match="bias_corrected"):
        allan_deviation(y, 1.0, kind="oadev", bias_corrected=True)
    with pytest.raises(FogbayesError, match=r"1\.\.300"):
        allan_deviation(y, 1.0, kind="htotdev", taus=[301])
    y[5] = np.nan
    with pytest.raises(FogbayesError, match="missing"):
        allan_deviation(y, 1.0, kind="htotdev")


def test_cli_kind_and_bias_corrected(tmp_path, capsys):
    """`fogbayes allan --kind htotdev --bias-corrected`: the document carries the deviation
    (equal to allan_deviation on the same rate), the report line names it; a ramp-free
    Hadamard total beside the OADEV fit. Wrong combinations end in one line naming the flag."""
    import json

    from fogbayes.cli import main
    from fogbayes.data import load

    rng = np.random.default_rng(7)
    y = rng.normal(size=3000) + 0.02 * np.arange(3000)  # white rate + a ramp, deg/h
    path = tmp_path / "r.csv"
    path.write_text("time,output\n" + "".join(f"{t:.1f},{v:.17g}\n" for t, v in enumerate(y)))
    assert main(["allan", str(path), "--json", "-", "--kind", "htotdev",
                 "--bias-corrected"]) == 0
    cap = capsys.readouterr()
    doc = json.loads(cap.out)
    d = doc["deviation"]
    assert d["kind"] == "htotdev" and d["bias_corrected"] is True
    rate = load(path).rate("deg/h")
    ref = allan_deviation(np.asarray(rate), 1.0, kind="htotdev", ci=0.9, bias_corrected=True)
    np.testing.assert_allclose(d["dev"], ref.dev, rtol=1e-12)
    np.testing.assert_allclose(d["dev_high"], ref.dev_high, rtol=1e-12)
    assert "htotdev, bias-corrected:" in cap.err
    oadev = allan_deviation(np.asarray(rate), 1.0, ci=0.9)  # the fitted curve stays OADEV
    np.testing.assert_allclose(doc["adev"], oadev.dev, rtol=1e-9)
    for args, flag in ((["--kind", "foo"], "--kind"),
                       (["--kind", "mdev", "--bias-corrected"], "--bias-corrected")):
        assert main(["allan", str(path), "--json", str(tmp_path / "x.json"), *args]) == 2
        err = capsys.readouterr().err.strip()
        assert err.count("\n") == 0 and flag in err and "Fix:" in err
