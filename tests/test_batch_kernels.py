"""The compiled per-sensor loops of the vectorised fit equal the NumPy/JAX functions they
stand in for, sensor by sensor (independent references: QR least squares, ``design``,
``pauta_flags``, ``block_average``)."""

from __future__ import annotations

import numpy as np
import pytest

from fogbayes.batch import block_kernels, kernels
from fogbayes.inference.lsq import lstsq
from fogbayes.models.polynomial import design, make_basis
from fogbayes.preprocess import pauta_flags
from fogbayes.preprocess.blocks import block_average, block_index

TERMS = ((0, 0), (1, 0), (0, 1), (2, 0), (1, 1), (0, 2))


def _problem(S=6, m=500, seed=0):
    rng = np.random.default_rng(seed)
    z = np.stack([rng.uniform(-40, 60, (S, m)), rng.normal(0, 2, (S, m))], axis=1)  # (S, c, m)
    T, r = z[:, 0], z[:, 1]
    y = 0.5 + 0.01 * T + 2e-4 * T**2 + 0.3 * r + 0.01 * T * r + rng.normal(0, 0.2, (S, m))
    w = rng.integers(1, 4, (S, m)).astype(float)
    return rng, z, y, w


def test_normal_equations_equal_qr_sensor_by_sensor_with_empty_rows():
    rng, z, y, w = _problem()
    w[:, rng.choice(500, 40, replace=False)] = 0.0  # empty blocks: NaN values, no weight
    z[np.broadcast_to(w[:, None, :] == 0, z.shape)] = np.nan
    y[w == 0] = np.nan
    lo, hi = kernels.covariate_range(z, w)
    bases = [make_basis(("T", "r"), TERMS, z[s][:, w[s] > 0].T) for s in range(len(y))]
    centre = np.array([b.centre for b in bases])
    scale = np.array([b.scale for b in bases])
    n_valid = (w > 0).sum(axis=1).astype(float)
    coef, cov, rss, s2, dof, ok = kernels.fit_gram(z, y, w, centre, scale, n_valid,
                                                     np.array(TERMS), 1e-10)
    for s, b in enumerate(bases):
        keep = w[s] > 0
        np.testing.assert_array_equal([lo[s], hi[s]], [z[s][:, keep].min(1), z[s][:, keep].max(1)])
        ref = lstsq(design(z[s][:, keep].T, b), y[s, keep], w[s, keep])
        # normal equations vs QR in a scaled basis (cond(X) ~ 10): rounding, ~1e-13
        np.testing.assert_allclose(coef[s], ref.params, rtol=1e-10, atol=1e-12)
        np.testing.assert_allclose(cov[s], ref.covariance, rtol=1e-9, atol=1e-15)
        assert rss[s] == pytest.approx(float(np.sum(ref.residual ** 2)), rel=1e-10)
        assert s2[s] == pytest.approx(float(ref.sigma2), rel=1e-10)
        assert dof[s] == keep.sum() - len(TERMS) and ok[s]


def test_rank_deficient_sensor_is_flagged_not_hidden():
    _, z, y, w = _problem(S=3)
    z[1, 1] = 0.5  # no temperature rate variation: the r, T*r, r^2 columns are collinear
    centre, scale = np.zeros((3, 2)), np.ones((3, 2))
    *_, ok = kernels.fit_gram(z, y, w, centre, scale, np.full(3, 500.0), np.array(TERMS), 1e-10)
    assert ok.tolist() == [True, False, True]


def test_bias_evaluation_with_and_without_clamping():
    rng, z, _, _ = _problem(S=4)
    coef = rng.normal(size=(4, len(TERMS)))
    bases = [make_basis(("T", "r"), TERMS, z[s].T) for s in range(4)]
    centre = np.array([b.centre for b in bases])
    scale = np.array([b.scale for b in bases])
    lo, hi = np.tile([-10.0, -1.0], (4, 1)), np.tile([30.0, 1.0], (4, 1))
    inf = np.full((4, 2), np.inf)
    free = kernels.evaluate(coef, z, centre, scale, np.array(TERMS), -inf, inf)
    held = kernels.evaluate(coef, z, centre, scale, np.array(TERMS), lo, hi)
    for s, b in enumerate(bases):
        np.testing.assert_allclose(free[s], design(z[s].T, b) @ coef[s], rtol=1e-12, atol=1e-12)
        zc = np.clip(z[s].T, lo[s], hi[s])
        np.testing.assert_allclose(held[s], design(zc, b) @ coef[s], rtol=1e-12, atol=1e-12)


def test_pauta_rows_equal_pauta_flags():
    rng = np.random.default_rng(4)
    r = rng.standard_t(4, (20, 2000))  # heavy tails: several passes
    r[3, 100:105] += 30.0
    r[7] = 0.0  # constant: threshold 0, nothing strictly beyond it
    mask, count, threshold, passes = kernels.pauta(r, 3.0, 100)
    for s in range(len(r)):
        ref = pauta_flags(r[s], n_sigma=3.0)
        assert (mask[s] == ref.mask).all() and count[s] == ref.count
        assert passes[s] == ref.iterations
        assert threshold[s] == pytest.approx(ref.threshold, rel=1e-12, abs=0)
    assert count.sum() > 20 and passes.max() > 2


def test_masked_block_means_equal_block_average():
    rng = np.random.default_rng(5)
    n = 1200
    t = 1.7e9 + np.cumsum(rng.uniform(0.09, 0.11, n))  # Unix times, irregular 10 Hz
    y = rng.normal(size=(3, n))
    z = rng.normal(size=(3, 2, n))
    use = rng.random((3, n)) > 0.1
    use[1, 200:260] = False  # whole blocks left out
    bi = block_index(t, 1.0, partial="drop")
    tm, ym, zm, cnt = block_kernels.masked_block_means(t, y, z, use, bi.start, bi.stop)
    for s in range(3):
        ref = block_average(np.column_stack([y[s], z[s].T]), 1.0, time=t, mask=~use[s])
        np.testing.assert_array_equal(cnt[s], ref.count)
        np.testing.assert_allclose(tm[s], ref.time, rtol=0, atol=1e-6)  # 1.7e9 s: ulp 2.4e-7
        got = np.column_stack([ym[s], zm[s].T])
        np.testing.assert_allclose(got, ref.mean, rtol=1e-12, atol=1e-14, equal_nan=True)
    assert (cnt[1] == 0).sum() >= 4


def test_residual_pauta_equals_pauta_of_the_residual():
    rng, z, y, _ = _problem(S=5, m=3000, seed=7)
    y[2, 40:43] += 25.0
    coef = rng.normal(size=(5, len(TERMS)))
    centre, scale = np.tile([10.0, 0.0], (5, 1)), np.tile([50.0, 6.0], (5, 1))
    inf = np.full((5, 2), np.inf)
    bias = kernels.evaluate(coef, z, centre, scale, np.array(TERMS), -inf, inf)
    mask, count = kernels.residual_pauta(y, coef, z, centre, scale, np.array(TERMS), 3.0, 100)
    ref_mask, ref_count, _, _ = kernels.pauta(y - bias, 3.0, 100)
    assert (mask == ref_mask).all() and (count == ref_count).all() and count[2] >= 3
