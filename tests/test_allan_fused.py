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


def _kernel(y, ms, kind, gaps=False, method="auto"):
    """``allan_variance`` at the union of the grids (one XLA compilation per shape and kind:
    most of this file's run time; ``mapped`` compiles in a quarter of the time)."""
    var, count = allan_variance(y, tuple(ms), kind=kind, gaps=gaps, method=method)
    return dict(zip(ms, np.asarray(var))), dict(zip(ms, np.asarray(count)))


def _brute(y, ms, kind):
    """The estimators straight from their definitions (NumPy), gaps excluded term by term."""
    bad = ~np.isfinite(y)
    x = np.concatenate([[0.0], np.cumsum(np.where(bad, 0.0, y - np.nanmean(y)))])
    out = []
    for m in ms:
        terms = []
        if kind == "ohdev":
            for i in range(x.size - 3 * m):
                if not bad[i:i + 3 * m].any():
                    terms.append(x[i + 3 * m] - 3 * x[i + 2 * m] + 3 * x[i + m] - x[i])
            norm = 6.0 * m**2
        else:
            for j in range(x.size - 3 * m + 1):
                if not bad[j:j + 3 * m - 1].any():
                    i = np.arange(j, j + m)
                    terms.append(np.sum(x[i + 2 * m] - 2 * x[i + m] + x[i]))
            norm = 2.0 * m**4
        t = np.asarray(terms)
        out.append((np.sum(t * t) / (norm * t.size) if t.size else np.nan, t.size))
    return np.array([o[0] for o in out]), np.array([o[1] for o in out], float)


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("noise", ["white", "random_walk"])
@pytest.mark.parametrize("n", [10_000, 2**14])
def test_matches_kernel_and_allantools(kind, noise, n):
    y = _data(noise, n, seed=n + len(noise))
    grids = _grids(n, kind)
    # 2^14: the kernels allan_deviation runs; 10 000: their lax.map variant (same sums)
    method = "auto" if n == 2**14 else "mapped"
    ref_var, ref_count = _kernel(y, sorted(set().union(*grids.values())), kind, method=method)
    for grid, ms in grids.items():
        var, count = mod_hadamard_variance(y, ms, kind)
        np.testing.assert_allclose(var, [ref_var[m] for m in ms], rtol=1e-9, atol=0,
                                   err_msg=grid)
        np.testing.assert_array_equal(count, [ref_count[m] for m in ms])
        if noise == "white":  # no wandering phase: the same sums to rounding
            np.testing.assert_allclose(var, [ref_var[m] for m in ms], rtol=1e-12)
        _, devs, _, _ = getattr(allantools, kind)(y, rate=1.0, data_type="freq",
                                                 taus=np.asarray(ms, float))
        # allantools' mdev forms S_{i+3m} - 3 S_{i+2m} + ... from the raw phase (~1e6 on this
        # random walk) and carries one running sum over the whole record: against a
        # long-double reference it is off by up to ~3e-7 here, the kernels by ~1e-11
        rtol = 1e-6 if (kind, noise) == ("mdev", "random_walk") else 1e-9
        np.testing.assert_allclose(var, devs**2, rtol=rtol, atol=0, err_msg=grid)


@pytest.mark.parametrize("kind", KINDS)
def test_offset_does_not_change_the_variance(kind):
    y = _data("white", 5000, seed=3)
    ms = (1, 2, 7, 100, 1000)
    a, _ = mod_hadamard_variance(y, ms, kind)
    b, _ = mod_hadamard_variance(y + 1e3, ms, kind)
    np.testing.assert_allclose(a, b, rtol=1e-9)


def _gappy(n, seed):
    rng = np.random.default_rng(seed)
    y = rng.normal(size=n) + 1.0
    y[rng.choice(n, size=max(1, n // 400), replace=False)] = np.nan
    y[n // 2:n // 2 + n // 250 + 1] = np.nan  # one longer gap
    return y


@pytest.mark.parametrize("kind", KINDS)
def test_gaps_match_kernel_with_gaps(kind):
    n = 10_000
    y = _gappy(n, seed=5)
    top = (n + 1) // 3 if kind == "mdev" else n // 3  # one term (or none: touches a gap)
    grids = {"octave": cluster_sizes(n, "octave", kind=kind), "other": (1, 3, 10, 50),
             "top": (top - 1, top)}
    ref_var, ref_count = _kernel(y, sorted(set().union(*grids.values())), kind, gaps=True)
    for grid, ms in grids.items():
        var, count = mod_hadamard_variance(y, ms, kind)
        want = np.array([ref_var[m] for m in ms])
        np.testing.assert_array_equal(count, [ref_count[m] for m in ms], err_msg=grid)
        np.testing.assert_array_equal(np.isnan(var), np.isnan(want))  # NaN: no term kept
        np.testing.assert_allclose(var, want, rtol=1e-10, equal_nan=True, err_msg=grid)
        assert (count < n + 1 - 3 * np.asarray(ms) + (kind == "mdev")).all()


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("n", [3, 4, 5, 11, 12, 40])
@pytest.mark.parametrize("gaps", [False, True])
def test_short_records_and_largest_clusters_by_definition(kind, n, gaps):
    y = _gappy(n, seed=n) if gaps and n > 5 else _data("white", n, seed=n)
    top = (n + 1) // 3 if kind == "mdev" else n // 3
    ms = tuple(range(1, top + 1))
    var, count = mod_hadamard_variance(y, ms, kind)
    ref_var, ref_count = _brute(y, ms, kind)
    np.testing.assert_array_equal(count, ref_count)
    np.testing.assert_allclose(var, ref_var, rtol=1e-10, equal_nan=True)


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
