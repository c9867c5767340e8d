"""The NUTS driver's ways of running chains (fogbayes.inference.nuts.chain_sampler).

Reference: a correlated 2-D normal, whose mean and covariance are known in closed form; and
"threads" against "sequential", which run the same single-chain steps and must give the
same draws bit for bit."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from fogbayes.inference.nuts import chain_sampler

_COV = np.array([[1.0, 0.8], [0.8, 2.0]])
_MEAN = np.array([1.0, -2.0])


def _potential(mean, prec):
    return lambda z: 0.5 * (z["x"] - mean) @ prec @ (z["x"] - mean)


def _draws(method):
    run = chain_sampler(_potential, 300, 1500, chain_method=method)
    keys = jax.random.split(jax.random.PRNGKey(3), 2)
    z0 = {"x": jnp.zeros((2, 2))}
    zs, div = run(keys, z0, jnp.asarray(_MEAN), jnp.asarray(np.linalg.inv(_COV)))
    return np.asarray(zs["x"]), np.asarray(div)


def test_threads_gives_the_draws_of_sequential_and_the_known_moments():
    seq, div_s = _draws("sequential")
    thr, div_t = _draws("threads")
    assert thr.shape == seq.shape == (2, 1500, 2)
    np.testing.assert_array_equal(thr, seq)
    np.testing.assert_array_equal(div_t, div_s)
    flat = thr.reshape(-1, 2)
    # 3000 draws (ESS ~ 1000+): the mean within 4 standard errors, the covariance within 15 %
    se = np.sqrt(np.diag(_COV) / 1000)
    assert np.all(np.abs(flat.mean(axis=0) - _MEAN) < 4 * se)
    np.testing.assert_allclose(np.cov(flat.T), _COV, rtol=0.15, atol=0.12)


def test_threads_needs_compiled_chains():
    with pytest.raises(ValueError, match="jit=True"):
        chain_sampler(_potential, 10, 10, chain_method="threads", jit=False)


def test_a_warm_start_keeps_the_carried_mass_and_adapts_the_step_size():
    """``return_adaptation`` gives each chain's adapted mass and step size; a chain started
    from them (``warm_start``) keeps that mass to the bit, adapts its step size in a short
    warm-up and still samples the known moments."""
    args = (jnp.asarray(_MEAN), jnp.asarray(np.linalg.inv(_COV)))
    keys = jax.random.split(jax.random.PRNGKey(5), 2)
    z0 = {"x": jnp.zeros((2, 2))}
    zs, div, (inverse_mass, step_size) = chain_sampler(
        _potential, 300, 500, chain_method="threads", return_adaptation=True)(keys, z0, *args)
    assert np.asarray(inverse_mass).shape == (2, 2, 2) and np.asarray(step_size).shape == (2,)
    # the adapted inverse mass estimates the covariance (300 warm-up steps: within ~35 %)
    np.testing.assert_allclose(np.asarray(inverse_mass).mean(axis=0), _COV, rtol=0.35,
                               atol=0.3)
    start = (jnp.asarray(np.asarray(inverse_mass).mean(axis=0)), jnp.asarray(1.0))
    warm = chain_sampler(_potential, 50, 1500, chain_method="threads", warm_start=True,
                         return_adaptation=True)
    zs, div, (kept, step) = warm(jax.random.split(jax.random.PRNGKey(6), 2), z0, start, *args)
    np.testing.assert_array_equal(np.asarray(kept), np.broadcast_to(start[0], (2, 2, 2)))
    assert np.all(np.asarray(step) != 1.0) and not np.asarray(div).any()
    flat = np.asarray(zs["x"]).reshape(-1, 2)
    se = np.sqrt(np.diag(_COV) / 1000)
    assert np.all(np.abs(flat.mean(axis=0) - _MEAN) < 4 * se)
    np.testing.assert_allclose(np.cov(flat.T), _COV, rtol=0.15, atol=0.12)
