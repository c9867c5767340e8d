"""The one-pass lag-1 sums give the noise identification of the plain two-pass formulas.

Reference: Riley & Greenhall's recipe written out directly in NumPy here (drop NaN, remove
the least-squares line, lag-1 autocorrelation of the d-times differenced series), against
:func:`fogbayes.stats.noise_id_sums.lag1_from_sums` and the library's ``identify_alphas``.
"""

from __future__ import annotations

import numpy as np
import pytest

from fogbayes.simulate.noise import allan_noise
from fogbayes.stats.noise_id import identify_alphas
from fogbayes.stats.noise_id_sums import lag1_from_sums, lag1_sums


def _r1(z):
    z = z - z.mean()
    return float(z[:-1] @ z[1:] / (z @ z))


def reference_r1(z, d):
    x = z[np.isfinite(z)]
    t = np.arange(x.size) - (x.size - 1) / 2
    w = x - x.mean() - t * (t @ x / (t @ t))
    return _r1(np.diff(w, d) if d else w)


def reference_alphas(y, ms, dmax, lo):
    out, last = [], 0
    for m in ms:
        n_cl = y.size // m
        z = y[:n_cl * m].reshape(n_cl, m).mean(axis=1)
        z = z[np.isfinite(z)]
        if z.size >= 30:
            for d in range(dmax + 1):
                delta = reference_r1(z, d) / (1 + reference_r1(z, d))
                if delta < 0.25 or d >= dmax:
                    last = int(np.clip(-np.round(2 * delta) - 2 * d, lo, 2))
                    break
        out.append(last)
    return out


def _series(kind, n, rng):
    if kind == "white":
        return rng.standard_normal(n)
    if kind == "walk":
        return np.cumsum(rng.standard_normal(n)) * 0.01 + rng.standard_normal(n)
    if kind == "flicker":
        return allan_noise(n, 1.0, B=1.0, N=0.2, seed=int(rng.integers(1 << 30)))
    if kind == "offset":  # a large bias over tiny noise: the shift keeps the digits
        return 1e6 + 1e-3 * rng.standard_normal(n)
    if kind == "ramp":  # the line carries nearly everything: the two-pass fallback
        return 1e3 * np.arange(n) / n + 1e-4 * rng.standard_normal(n)
    raise ValueError(kind)


@pytest.mark.parametrize("gaps", [True, False])
@pytest.mark.parametrize("kind", ["white", "walk", "flicker", "offset", "ramp"])
def test_lag1_sums_match_the_two_pass_formulas(kind, gaps):
    rng = np.random.default_rng(7)
    z = _series(kind, 20_000, rng)
    if gaps:  # dropped clusters: their neighbours adjoin
        z[rng.integers(0, z.size, 50)] = np.nan
    sums = lag1_sums(z)
    assert sums[0] == np.isfinite(z).sum()
    for d in range(4):
        got = lag1_from_sums(sums, d)
        if kind == "ramp" and d == 0:  # the line is ~all the variance: the guard declines
            assert got is None
            continue
        assert abs(got - reference_r1(z, d)) < 1e-9, d


@pytest.mark.parametrize("kind", ["white", "walk", "flicker", "offset", "ramp"])
@pytest.mark.parametrize("dev", ["oadev", "ohdev"])
def test_identified_alphas_equal_the_reference(kind, dev):
    rng = np.random.default_rng(11)
    y = _series(kind, 1 << 17, rng)
    y[rng.integers(0, y.size, 30)] = np.nan
    ms = [1 << k for k in range(13)]
    hadamard = dev == "ohdev"
    want = reference_alphas(y, ms, 3 if hadamard else 2, -4 if hadamard else -2)
    assert identify_alphas(y, ms, kind=dev).tolist() == want

