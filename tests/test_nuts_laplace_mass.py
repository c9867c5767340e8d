"""The warm-up's starting inverse mass matrix: the Laplace approximation at the chain's start.

References are closed forms: for a Gaussian potential 0.5 (z - m)' A (z - m) the inverse
Hessian is A^-1 everywhere; directions of negative or tiny curvature start at unit inverse
mass (NumPyro's default)."""

import jax.numpy as jnp
import numpy as np

import fogbayes  # noqa: F401  (float64)
from fogbayes.inference.nuts import MIN_CURVATURE, laplace_inverse_mass


def _gaussian(A, m):
    A, m = jnp.asarray(A), jnp.asarray(m)

    def potential(z):
        d = jnp.concatenate([jnp.atleast_1d(z["a"]), z["b"]]) - m
        return 0.5 * d @ A @ d

    return potential


def test_inverse_hessian_of_a_gaussian_potential():
    rng = np.random.default_rng(0)
    B = rng.standard_normal((3, 3))
    cov = B @ B.T + np.diag([1e-4, 1.0, 10.0])  # sd 0.01 to ~3.5, correlated
    A = np.linalg.inv(cov)
    z0 = {"a": jnp.asarray(0.3), "b": jnp.asarray([1.0, -2.0])}
    inv = np.asarray(laplace_inverse_mass(_gaussian(A, [0.1, 0.2, 0.3]), z0))
    np.testing.assert_allclose(inv, cov, rtol=1e-10, atol=1e-12)
    diag = np.asarray(laplace_inverse_mass(_gaussian(A, [0.1, 0.2, 0.3]), z0, dense_mass=False))
    np.testing.assert_allclose(diag, np.diag(cov), rtol=1e-10)


def test_untrusted_curvature_starts_at_unit_inverse_mass():
    # eigenvalues 4 (kept), -3 (a start off the mode: replaced) and MIN_CURVATURE / 2 (flat)
    Q, _ = np.linalg.qr(np.random.default_rng(1).standard_normal((3, 3)))
    lam = np.array([4.0, -3.0, MIN_CURVATURE / 2])
    A = (Q * lam) @ Q.T
    z0 = {"a": jnp.asarray(0.0), "b": jnp.zeros(2)}
    inv = np.asarray(laplace_inverse_mass(_gaussian(A, np.zeros(3)), z0))
    expect = (Q * np.array([0.25, 1.0, 1.0])) @ Q.T
    np.testing.assert_allclose(inv, expect, atol=1e-12)


def test_a_nan_hessian_falls_back_to_the_identity():
    z0 = {"a": jnp.asarray(-1.0), "b": jnp.ones(2)}
    inv = laplace_inverse_mass(lambda z: jnp.sqrt(z["a"]) + jnp.sum(z["b"] ** 2), z0)
    np.testing.assert_array_equal(np.asarray(inv), np.eye(3))
