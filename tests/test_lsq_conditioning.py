"""Condition numbers of a fleet fit from its covariances agree with the design's SVD.

A fleet fit keeps ``Cov = s^2 (X^T W X)^-1`` per sensor, not the design, so its
identifiability check reads the singular values of ``sqrt(w) X`` from the eigenvalues of
``Cov / s^2`` (``1 / s_i^2``), all sensors in one stacked eigendecomposition. The
reference is :func:`conditioning`: QR and SVD of the weighted design itself.
"""

from __future__ import annotations

import numpy as np

from fogbayes.inference.lsq import (conditioning, conditioning_from_covariance,
                                    conditionings_from_covariances)


def _designs(rng, n=400):
    t = np.linspace(-1, 1, n)
    good = np.column_stack([np.ones(n), t, t ** 2 - 1 / 3, rng.normal(size=n)])
    near = good.copy()
    near[:, 3] = t + 1e-5 * rng.normal(size=n)  # a covariate that is almost the time
    return [good, near, np.column_stack([np.ones(n), t, 2 * t, t ** 2])]  # last: rank 3


def test_stacked_conditioning_matches_the_design_svd():
    rng = np.random.default_rng(3)
    designs = _designs(rng)
    w = rng.uniform(0.5, 2.0, designs[0].shape[0])
    s2 = np.array([0.7, 2.5, 1.3])
    covs = np.stack([s * np.linalg.pinv(X.T @ (w[:, None] * X)) for X, s in zip(designs, s2)])
    got = conditionings_from_covariances(covs, s2)
    for X, g, cov, s in zip(designs[:2], got, covs, s2):
        ref = conditioning(X, w)
        # the covariance went through X^T W X and its inverse: relative precision
        # kappa^2 * eps, not kappa * eps (kappa 1.4e5 for the near-collinear design)
        tol = max(1e-12, 100 * ref.condition_number ** 2 * np.finfo(float).eps)
        np.testing.assert_allclose(g.singular_values, ref.singular_values, rtol=tol)
        np.testing.assert_allclose(g.condition_number, ref.condition_number, rtol=tol)
        # singular vectors up to sign: |v_ref . v_got| = 1 for each direction
        np.testing.assert_allclose(np.abs(np.sum(g.vectors * ref.vectors, axis=1)), 1.0,
                                   atol=tol)
        one = conditioning_from_covariance(cov, s)  # the one-fit form is the same code
        np.testing.assert_array_equal(one.singular_values, g.singular_values)
    assert got[0].condition_number < 1e2 and got[1].condition_number > 1e4
    assert got[2].condition_number == np.inf and got[2].singular_values[-1] == 0.0


def test_a_fit_without_a_variance_has_no_condition_number():
    cov = np.stack([np.eye(3), np.full((3, 3), np.nan), np.eye(3)])
    got = conditionings_from_covariances(cov, np.array([1.0, 1.0, 0.0]))
    assert got[0].condition_number == 1.0
    assert all(g.condition_number == np.inf and np.isnan(g.singular_values).all()
               for g in got[1:])
