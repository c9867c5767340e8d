"""B1 / R(n) noise identification below 30 cluster means, and Stable32's MTOTDEV EDF switch.

* The B1 expectations against simulation (ratio of mean standard variance, normalised by
  N - 1, to mean non-overlapping AVAR of N means): white FM 1, white PM (N^2-1)/(1.5 N(N-1)).
* Identification of simulated white PM (20 means) and a check that PHASE.DAT's MTOTDEV,
  TTOTDEV and HTOTDEV alphas below 30 means are Stable32's (all rows: the end-to-end tests in
  ``test_stable32_phasedat_totals.py``; here the rows the lag-1 ACF cannot reach).
* Stable32's MTOTDEV EDF switches from Greenhall's MDEV EDF to its line at m = 10, not at
  T/tau = 100: its decade table of the 1 253-point Sr-87 record (Stable32 1.60, in
  allantoolkit's ``tests/assets/Sr87/phase/decade/mtotdev.txt``, amv213/allantoolkit) prints
  m = 10, alpha 0, sigma 6.7260e-17, bounds 6.3861e-17 / 7.1270e-17 at T/tau = 125.2.
"""

from __future__ import annotations

import numpy as np
import pytest
from test_stable32_phasedat_totals import _rate, _table

from fogbayes.stats.allan import allan_deviation
from fogbayes.stats.edf import chi2_interval, edf_greenhall
from fogbayes.stats.edf_total import edf_mtotdev_stable32
from fogbayes.stats.noise_id import identify_alphas
from fogbayes.stats.noise_id_b1 import b1_expected, b1_rn_alpha


@pytest.mark.parametrize("mu,make", [(-1, lambda r, N: r.normal(size=N)),
                                     (-2, lambda r, N: np.diff(r.normal(size=N + 1)))])
def test_b1_expectation_matches_simulation(mu, make):
    rng, N = np.random.default_rng(0), 10
    s2, av = [], []
    for _ in range(20000):
        z = make(rng, N)
        s2.append(np.var(z, ddof=1))
        av.append(0.5 * np.mean(np.diff(z) ** 2))
    # measured 0.25 % (white FM), 0.13 % (white PM) off; 20 000 records: ~1 % sd
    assert np.mean(s2) / np.mean(av) == pytest.approx(b1_expected(N, mu), rel=0.03)


def test_white_pm_identified_from_twenty_means():
    hits = [b1_rn_alpha(np.diff(np.random.default_rng(s).normal(size=2001)), 100)
            for s in range(20)]
    assert hits.count(2) >= 16  # measured 18 of 20


@pytest.mark.parametrize("kind,name,rules", [
    ("mtotdev", "phase_dat_mtotdev_octave.txt", "mdev"),
    ("mtotdev", "phase_dat_mtotdev_decade.txt", "mdev"),
    ("ttotdev", "phase_dat_ttotdev_octave.txt", "mdev"),
    ("htotdev", "phase_dat_htotdev_octave.txt", "ohdev")])
def test_stable32_alphas_below_thirty_means(kind, name, rules):
    t = _table(name)
    ms, alpha = t[:, 0].astype(int), t[:, 3].astype(int)
    few = 1000 // ms < 30  # m = 64 ... 256: alpha 0 at 64, 1 from 100 on
    y = _rate()
    res = allan_deviation(y, 1.0, taus=ms, kind=kind, ci=0.683)
    np.testing.assert_array_equal(res.alpha[few], alpha[few])
    carried = identify_alphas(y, ms, kind=rules)  # the lag-1 ACF carried forward misses
    assert (carried[few] != alpha[few]).any()


def test_mtotdev_edf_switch_is_m_ten():
    N, m, sigma, lo, hi = 1253, 10, 6.7260e-17, 6.3861e-17, 7.1270e-17
    vlo, vhi = chi2_interval(sigma**2, edf_mtotdev_stable32(0, m, N), ci=0.683)
    err = max(abs(np.sqrt(vlo) / lo - 1), abs(np.sqrt(vhi) / hi - 1))
    assert err < 1e-3  # measured 3e-4
    glo, ghi = chi2_interval(sigma**2, edf_greenhall(0, 2, m, N, overlapping=True,
                                                     modified=True), ci=0.683)
    assert abs(np.sqrt(ghi) / hi - 1) > 5e-3  # the T/tau > 100 rule: 1.1 % off
