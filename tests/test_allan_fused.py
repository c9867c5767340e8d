"""Compiled mdev / ohdev (allan_fused) against the XLA kernels and allantools."""

from __future__ import annotations

import numpy as np
import pytest

from fogbayes.stats.allan_fused import mod_hadamard_variance
from fogbayes.stats.allan_kernels import allan_variance
from fogbayes.stats.taus import cluster_sizes

allantools = pytest.importorskip("allantools")

KINDS = ("mdev", "ohdev")


def _data(noise: str, n: int, seed: int) -> np.ndarray:
    y = np.random.default_rng(seed).normal(size=n) + 2.5  # an offset: must not matter
    return np.cumsum(y) if noise == "random_walk" else y


def _grids(n, kind):
    return {"octave": cluster_sizes(n, "octave", kind=kind), "other": (1, 3, 10, 50)}


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("noise", ["white", "random_walk"])
@pytest.mark.parametrize("n", [10_000, 2**14])
def test_matches_kernel_and_allantools(kind, noise, n):
    y = _data(noise, n, seed=n + len(noise))
    for grid, ms in _grids(n, kind).items():
        var, count = mod_hadamard_variance(y, ms, kind)
        ref_var, ref_count = (np.asarray(a) for a in allan_variance(y, ms, kind=kind))
        np.testing.assert_allclose(var, ref_var, rtol=1e-9, atol=0, err_msg=grid)
        np.testing.assert_array_equal(count, ref_count)
        _, devs, _, _ = getattr(allantools, kind)(y, rate=1.0, data_type="freq",
                                                 taus=np.asarray(ms, float))
        # allantools' mdev forms S_{i+3m} - 3 S_{i+2m} + ... from the raw phase (~1e6 on this
        # random walk) and carries one running sum over the whole record: against a
        # long-double reference it is off by up to ~3e-7 here, the kernels by ~1e-11
        rtol = 1e-6 if (kind, noise) == ("mdev", "random_walk") else 1e-9
        np.testing.assert_allclose(var, devs**2, rtol=rtol, atol=0, err_msg=grid)


@pytest.mark.parametrize("kind", KINDS)
def test_white_noise_close_to_kernel_to_rounding(kind):
    y = _data("white", 2**14, seed=7)
    ms = cluster_sizes(y.size, "octave", kind=kind)
    var, _ = mod_hadamard_variance(y, ms, kind)
    ref, _ = allan_variance(y, ms, kind=kind)
    np.testing.assert_allclose(var, np.asarray(ref), rtol=1e-12)


@pytest.mark.parametrize("kind", KINDS)
def test_offset_does_not_change_the_variance(kind):
    y = _data("white", 5000, seed=3)
    ms = (1, 2, 7, 100, 1000)
    a, _ = mod_hadamard_variance(y, ms, kind)
    b, _ = mod_hadamard_variance(y + 1e3, ms, kind)
    np.testing.assert_allclose(a, b, rtol=1e-9)


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("n", [10_000, 9001, 40])
def test_gaps_match_kernel_with_gaps(kind, n):
    rng = np.random.default_rng(n)
    y = rng.normal(size=n) + 1.0
    y[rng.choice(n, size=max(1, n // 400), replace=False)] = np.nan
    y[n // 2:n // 2 + n // 250 + 1] = np.nan  # one longer gap
    top = (n + 1) // 3 if kind == "mdev" else n // 3
    for ms in (cluster_sizes(n, "octave", kind=kind), (1, 3, 10), (top,)):
        var, count = mod_hadamard_variance(y, ms, kind)
        ref_var, ref_count = (np.asarray(a) for a in allan_variance(y, ms, kind=kind, gaps=True))
        np.testing.assert_array_equal(count, ref_count)
        np.testing.assert_array_equal(np.isnan(var), np.isnan(ref_var))  # NaN: no term kept
        np.testing.assert_allclose(var, ref_var, rtol=1e-10, equal_nan=True)
        assert (count < np.asarray([n + 1 - 3 * m + (kind == "mdev") for m in ms])).all()


@pytest.mark.parametrize("kind", KINDS)
def test_largest_cluster_and_short_records(kind):
    for n in (3, 4, 5, 11, 12):
        y = _data("white", n, seed=n)
        top = (n + 1) // 3 if kind == "mdev" else n // 3
        ms = tuple(range(1, top + 1))
        var, count = mod_hadamard_variance(y, ms, kind)
        ref_var, ref_count = (np.asarray(a) for a in allan_variance(y, ms, kind=kind))
        np.testing.assert_allclose(var, ref_var, rtol=1e-10)
        np.testing.assert_array_equal(count, ref_count)


def test_rejects_bad_input():
    y = np.ones(30)
    with pytest.raises(ValueError, match="kind"):
        mod_hadamard_variance(y, (1,), "oadev")
    with pytest.raises(ValueError, match="cluster sizes"):
        mod_hadamard_variance(y, (11,), "ohdev")
    with pytest.raises(ValueError, match="cluster sizes"):
        mod_hadamard_variance(y, (0, 1), "mdev")
    with pytest.raises(ValueError, match="finite"):
        mod_hadamard_variance(np.full(30, np.nan), (1,), "mdev")
    with pytest.raises(ValueError, match="1-D"):
        mod_hadamard_variance(np.ones((2, 30)), (1,), "mdev")
