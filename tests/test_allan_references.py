"""Allan deviations against published references on measured data (../shared/data/measured).

* allantools ``oadev`` on the six ADIS16405 static runs (1e6 samples each), 1e-9 relative;
* Stable32's all-tau deviations of the measured OCXO record, to the printed digits;
* Stable32's octave confidence intervals and noise identification;
* the published Haar wavelet variance and maximal-overlap AVAR of ADIS run 1.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from fogbayes.stats.allan import allan_deviation
from fogbayes.stats.edf import chi2_interval, edf_for_kind, edf_greenhall
from fogbayes.stats.noise_id import identify_alpha

allantools = pytest.importorskip("allantools")
pytestmark = pytest.mark.measured

ADIS = "adis16405_static_ucalgary"
OCXO = "allantools_ocxo_stable32"
FS_ADIS = 100.0


def _adis(measured, run):
    return np.load(measured(ADIS, f"adis_16405_imu{run}.npz"))["data"]


def _ocxo(measured):
    # allantools' own test: y = f / 1e7 - 1 (fractional frequency), rate 1 Hz
    return np.loadtxt(measured(OCXO, "ocxo_frequency.txt")) / 1e7 - 1.0


@pytest.mark.parametrize("run", [1, 2, 3, 4, 5, 6])
def test_oadev_equals_allantools_on_adis_runs(measured, run):
    data = _adis(measured, run)
    for ch in range(3):  # the three gyro axes, deg/s
        y = data[:, ch]
        ref = allantools.oadev(y, rate=FS_ADIS, data_type="freq", taus="octave")
        ms = tuple(int(round(t * FS_ADIS)) for t in ref[0])
        res = allan_deviation(y, FS_ADIS, taus=ms)
        # both subtract the mean before a float64 cumulative sum; measured ~1e-13
        np.testing.assert_allclose(res.dev, ref[1], rtol=1e-9)
        np.testing.assert_array_equal(res.n_terms, ref[3])


def _within_print_rounding(ours, printed):
    """True where ``ours`` rounds to ``printed`` (5 significant digits), allowing for values
    within 1e-6 (relative) of a rounding boundary: Stable32 read the data from its own text
    file, and its non-overlapping results (fewer terms) differ from the exact float64 sums by
    up to ~2e-7 relative, so ties may round either way (measured worst: 0.507 of a unit)."""
    exp = np.floor(np.log10(np.abs(printed)))
    half_unit = 0.5e-4 * 10.0**exp
    return np.abs(ours - printed) <= half_unit + 1e-6 * np.abs(printed)


@pytest.mark.parametrize("kind", ["oadev", "adev", "mdev", "ohdev", "hdev", "tdev"])
def test_reproduces_stable32_alltau(measured, kind):
    y = _ocxo(measured)
    table = np.loadtxt(measured(OCXO, f"stable32_{kind}_alltau.txt"), comments="#")
    ms = tuple(int(m) for m in table[:, 0])
    res = allan_deviation(y, 1.0, taus=ms, kind=kind)
    np.testing.assert_array_equal(res.n_terms, table[:, 2])  # the "#" column
    assert np.all(_within_print_rounding(res.dev, table[:, 5]))
    exact = np.mean([f"{v:.4e}" == f"{p:.4e}" for v, p in zip(res.dev, table[:, 5])])
    # measured: oadev/mdev/tdev 272 of 273 identical strings, adev/hdev/ohdev 258-270 of
    # 261-273
    assert exact > 0.98


@pytest.mark.parametrize("kind", ["oadev", "adev", "mdev", "ohdev", "hdev", "tdev"])
def test_confidence_intervals_match_stable32_octave(measured, kind):
    y = _ocxo(measured)
    table = np.loadtxt(measured(OCXO, f"{kind}_octave.txt"), comments="#")
    ms, alpha, lo, sigma, hi = (table[:, 0].astype(int), table[:, 3].astype(int), table[:, 4],
                                table[:, 5], table[:, 6])
    base = "mdev" if kind == "tdev" else kind  # TDEV = tau MDEV / sqrt 3: the same EDF
    edf = edf_for_kind(alpha, ms, y.size, base)  # Stable32's own noise type per tau
    vlo, vhi = chi2_interval(sigma**2, edf, ci=0.683)
    # Stable32 prints 5 digits and uses Greenhall's tables where we sum exactly (~4e-4 apart)
    np.testing.assert_allclose(np.sqrt(vlo), lo, rtol=1e-3)
    np.testing.assert_allclose(np.sqrt(vhi), hi, rtol=1e-3)
    # lag-1 ACF noise ID is what Stable32 uses with >= 30 averaged points
    enough = y.size // ms >= 30
    ours = [identify_alpha(y, int(m), dmax=3 if "h" in kind else 2) for m in ms[enough]]
    assert ours == alpha[enough].tolist()


def test_edf_matches_allantools_where_it_sums_exactly():
    ci = pytest.importorskip("allantools.ci")
    for alpha in (2, 1, 0, -1, -2):
        for m, n_phase, ov, mod, d in [(1, 1001, True, False, 2), (4, 5001, True, False, 2),
                                       (8, 2001, False, False, 2), (16, 20001, True, True, 2),
                                       (5, 3001, True, False, 3)]:
            ref = ci.edf_greenhall(alpha, d, m, n_phase, overlapping=ov, modified=mod)
            got = edf_greenhall(alpha, d, m, n_phase, overlapping=ov, modified=mod)
            assert got == pytest.approx(ref, rel=1e-9), (alpha, m, ov, mod, d)


def test_haar_wavelet_variance_of_adis_run1(measured):
    """2 x Haar MODWT variance at scale s equals the overlapping AVAR at tau = s / 2."""
    data = _adis(measured, 1)
    ref = pd.read_csv(measured(ADIS, "adis_wv_reference_imu1.csv"))
    for j, (ch, rows) in enumerate(ref.groupby("channel", sort=False)):
        ms = tuple(int(round(t * FS_ADIS / 2)) for t in rows["tau_s"])
        res = allan_deviation(data[:, j], FS_ADIS, taus=ms, m_max=max(ms))
        # the reference is printed with 11 significant digits: measured agreement ~4e-11
        np.testing.assert_allclose(res.var, 2 * rows["haar_wv"].to_numpy(), rtol=1e-9,
                                   err_msg=ch)


def test_published_maximal_overlap_avar_of_adis_run1(measured):
    data = _adis(measured, 1)
    ref = pd.read_csv(measured(ADIS, "adis_av_reference_imu1.csv"))
    for j, (ch, rows) in enumerate(ref.groupby("channel", sort=False)):
        ms = tuple(int(m) for m in rows["m_samples"])
        res = allan_deviation(data[:, j], FS_ADIS, taus=ms, m_max=max(ms))
        # The R package 'avar' itself differs from allantools and from the Haar WV (which we
        # match to 4e-11) by up to 6e-6 relative (SOURCE.md measured <= 6e-6): its own
        # rounding, not ours.
        np.testing.assert_allclose(res.var, rows["mo_avar"].to_numpy(), rtol=1e-5, err_msg=ch)


def test_tdev_equals_allantools_and_scales_mdev(measured):
    y = _ocxo(measured)
    ref = allantools.tdev(y, rate=1.0, data_type="freq", taus="octave")
    ms = tuple(int(round(t)) for t in ref[0])
    res = allan_deviation(y, 1.0, taus=ms, kind="tdev")
    np.testing.assert_allclose(res.dev, ref[1], rtol=1e-9)  # measured 3e-14
    mod = allan_deviation(y, 1.0, taus=ms, kind="mdev")
    f = res.tau / np.sqrt(3.0)  # NIST SP 1065 eq. 17, intervals included
    np.testing.assert_allclose(res.dev_low, mod.dev_low * f, rtol=1e-12)
    np.testing.assert_allclose(res.dev_high, mod.dev_high * f, rtol=1e-12)
    assert res.kind == "tdev" and np.array_equal(res.alpha, mod.alpha)
