"""Allan-family deviations against allantools, brute force and closed forms."""

from __future__ import annotations

import jax
import numpy as np
import pytest

from fogbayes.errors import FogbayesError, TooShortError
from fogbayes.stats.allan import allan_deviation
from fogbayes.stats.allan_kernels import allan_sums, allan_variance
from fogbayes.stats.taus import TauGridError, cluster_sizes

allantools = pytest.importorskip("allantools")

KINDS = {"oadev": "oadev", "adev": "adev", "mdev": "mdev", "ohdev": "ohdev", "hdev": "hdev"}


def _gyro_like(n, seed):
    """White + random-walk rate on a large offset: the offset stresses the cumulative sum."""
    rng = np.random.default_rng(seed)
    return 250.0 + rng.normal(size=n) + 0.02 * np.cumsum(rng.normal(size=n))


@pytest.mark.parametrize("kind", list(KINDS))
def test_matches_allantools_on_random_data(kind):
    y = _gyro_like(20_000, 1)
    ms = (1, 2, 3, 5, 8, 16, 50, 128, 333, 1000, 2000)
    ref = getattr(allantools, kind)(y, rate=1.0, data_type="freq", taus=np.array(ms, float))
    res = allan_deviation(y, 1.0, taus=ms, kind=kind)
    idx = [ms.index(int(t)) for t in ref[0]]
    # Both are float64 cumulative sums of mean-removed data: agreement to ~1e-13 is expected;
    # 1e-9 is the acceptance threshold.
    np.testing.assert_allclose(res.dev[idx], ref[1], rtol=1e-9)
    np.testing.assert_array_equal(res.n_terms[idx], ref[3])


@pytest.mark.parametrize("method", ["direct", "chunked", "mapped"])
def test_kernel_paths_agree(method):
    y = _gyro_like(40_000, 2)
    ms = cluster_sizes(y.size, "dense", per_decade=7)
    ref, _ = allan_variance(y, ms, method="direct")
    got, count = allan_variance(y, ms, method=method)
    np.testing.assert_allclose(got, ref, rtol=1e-12)  # same sums, other summation order
    assert np.all(np.asarray(count) == y.size + 1 - 2 * np.array(ms))


@pytest.mark.parametrize("taus", ["octave", "dense"])
def test_blocked_default_equals_the_jitted_kernels_with_gaps_and_batches(taus):
    # allan_deviation's CPU default for oadev (NumPy accumulators) against the XLA kernels,
    # on a batch whose second sensor has NaN gaps: same variances, same kept-term counts
    Y = np.stack([_gyro_like(30_000, 5), _gyro_like(30_000, 6)])
    Y[1, 1000:1010] = np.nan
    Y[1, 20_000] = np.nan
    got = allan_deviation(Y, 2.0, taus=taus)
    ref = allan_deviation(Y, 2.0, taus=taus, method="chunked")
    np.testing.assert_allclose(got.var, ref.var, rtol=1e-11)
    np.testing.assert_array_equal(got.n_terms, ref.n_terms)
    np.testing.assert_array_equal(got.excluded, ref.excluded)
    with pytest.raises(FogbayesError, match="oadev only"):
        allan_deviation(Y[0], 2.0, kind="mdev", method="blocked")


def test_batch_vmap_equals_rows_and_compiles_once():
    Y = np.stack([_gyro_like(5000, s) for s in range(4)])
    ms = (1, 4, 16, 64)
    batch, _ = allan_variance(Y, ms)
    for row, v in zip(Y, np.asarray(batch)):
        np.testing.assert_allclose(allan_variance(row, ms)[0], v, rtol=1e-13)
    # the per-sensor kernel is vmap-able too (the accelerator path of allan_variance)
    sums, counts = jax.vmap(lambda y: allan_sums(y, ms, method="direct"))(Y)
    np.testing.assert_allclose(np.asarray(sums) / (2.0 * np.array(ms) ** 2 * np.asarray(counts)),
                               batch, rtol=1e-12)
    allan_sums._clear_cache()
    allan_sums(Y[0], ms)
    allan_sums(Y[1], ms)
    assert allan_sums._cache_size() == 1  # new data, same static grid: no recompilation


def _brute_force(y, m, kind):
    """Term-by-term definition, skipping any term whose samples include a NaN."""
    x = np.concatenate([[0.0], np.cumsum(np.where(np.isnan(y), 0.0, y - np.nanmean(y)))])
    bad = np.concatenate([[0], np.cumsum(np.isnan(y))])
    terms = []
    if kind in ("oadev", "adev"):
        step = 1 if kind == "oadev" else m
        for i in range(0, y.size + 1 - 2 * m, step):
            if bad[i + 2 * m] == bad[i]:
                terms.append(((x[i + 2 * m] - 2 * x[i + m] + x[i]) / m) ** 2 / 2)
    elif kind == "ohdev":
        for i in range(0, y.size + 1 - 3 * m):
            if bad[i + 3 * m] == bad[i]:
                v = x[i + 3 * m] - 3 * x[i + 2 * m] + 3 * x[i + m] - x[i]
                terms.append((v / m) ** 2 / 6)
    elif kind == "mdev":
        for j in range(0, y.size + 2 - 3 * m):
            if bad[j + 3 * m - 1] == bad[j]:
                v = sum(x[i + 2 * m] - 2 * x[i + m] + x[i] for i in range(j, j + m))
                terms.append(v**2 / (2 * m**4))
    return np.mean(terms), len(terms)


@pytest.mark.parametrize("kind", ["oadev", "adev", "ohdev", "mdev"])
def test_gaps_exclude_every_touched_term(kind):
    y = _gyro_like(600, 3)
    y[100:104] = np.nan
    y[350] = np.nan
    ms = (1, 3, 7, 20, 45)
    res = allan_deviation(y, 2.0, taus=ms, kind=kind)
    for t, m in enumerate(ms):
        ref, count = _brute_force(y, m, kind)
        assert res.n_terms[t] == count
        np.testing.assert_allclose(res.var[t], ref, rtol=1e-11)
    assert res.n_missing == 5 and res.excluded.sum() > 0 and "excluded" in res.note


def test_long_record_precision_against_extended_precision():
    """1e6 samples with a large offset and drift: compare with a long-double computation."""
    rng = np.random.default_rng(4)
    n = 1_000_000
    y = 1e4 + 3.0 * np.linspace(-1, 1, n) + rng.normal(size=n) + 0.01 * np.cumsum(rng.normal(size=n))
    ms = (1, 16, 1024, 65536)
    yl = y.astype(np.longdouble)
    S = np.concatenate([[0], np.cumsum(yl - yl.mean())])
    ref = np.array([np.mean((S[2 * m:] - 2 * S[m:-m] + S[:-2 * m]) ** 2) / (2 * m * m) for m in ms],
                   dtype=float)
    got = allan_deviation(y, 1.0, taus=ms).var
    # long double carries 11 more bits; the float64 result is expected within ~1e-12
    np.testing.assert_allclose(got, ref, rtol=1e-10)


@pytest.mark.parametrize("noise,slope", [("white", -0.5), ("rrw", 0.5), ("quant", -1.0)])
def test_closed_form_slopes(noise, slope):
    rng = np.random.default_rng(5)
    n = 200_000
    y = {"white": rng.normal(size=n), "rrw": np.cumsum(rng.normal(size=n)),
         "quant": np.diff(rng.normal(size=n + 1))}[noise]
    res = allan_deviation(y, 1.0, taus=(4, 8, 16, 32, 64, 128, 256))
    fitted = np.polyfit(np.log(res.tau), np.log(res.dev), 1)[0]
    # 7 octaves with EDF >= ~700 each: slope standard error ~0.01 (rrw ~0.02); 0.05 is wide
    assert abs(fitted - slope) < 0.05
    assert set(res.alpha.tolist()) == {{"white": 0, "rrw": -2, "quant": 2}[noise]}


def test_grids():
    assert cluster_sizes(1000, "octave") == (1, 2, 4, 8, 16, 32, 64, 128)  # m <= 1001 // 4
    assert cluster_sizes(10_000, "decade")[:6] == (1, 2, 4, 10, 20, 40)
    dense = cluster_sizes(100_000, "dense", per_decade=20)
    ratios = np.diff(np.log10(dense))
    assert dense[0] == 1 and np.all(ratios > 0) and np.max(ratios[20:]) < 0.06
    assert cluster_sizes(40, "all") == tuple(range(1, 11))
    with pytest.raises(TauGridError, match="unknown tau grid"):
        cluster_sizes(1000, "weekly")


def test_bad_input_raises_specific_errors():
    with pytest.raises(TooShortError):
        allan_deviation(np.ones(2), 1.0)
    with pytest.raises(FogbayesError, match="inf"):
        allan_deviation(np.array([1.0, np.inf, 2.0, 3.0]), 1.0)
    with pytest.raises(TooShortError, match="cluster sizes"):
        allan_deviation(np.ones(100), 1.0, taus=(10, 80))
    with pytest.raises(FogbayesError, match="sample rate"):
        allan_deviation(np.ones(100), 0.0)


def test_chi2_interval_brackets_estimate_and_widens_with_tau():
    y = np.random.default_rng(6).normal(size=50_000)
    res = allan_deviation(y, 10.0)
    assert np.all(res.dev_low < res.dev) and np.all(res.dev < res.dev_high)
    width = np.log(res.dev_high / res.dev_low)
    assert np.all(np.diff(width) > 0)
    assert jax.numpy.asarray(res.var).dtype == np.float64
