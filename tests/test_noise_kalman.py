"""The CPU likelihoods the noise fits maximise equal their JAX definitions, gradients included.

:func:`fogbayes.inference.noise_kalman.negloglik` (forward sensitivities in a Numba loop) is
held to ``noise_ssm._negll_and_grad`` and ``reml._negreml_and_grad`` (the same filter and
profile, differentiated by JAX), on every noise structure the loop fits, with missing blocks,
unequal white weights and a design whose columns dwarf the noise (the precision case of
noise_ssm's module doc). The derivatives of the state-space system are checked against JAX's
``jacfwd`` of ``noise_ssm.system``. Both sides are exact arithmetic of the same expressions,
so they agree to rounding: 1e-9 relative is a thousand times the differences measured.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from fogbayes.loop.reml import _negreml_and_grad
from fogbayes.inference import noise_kalman as nk
from fogbayes.inference import noise_ssm as ns

CASES = [  # n blocks, Markov components, walk, flicker, theta
    (400, 0, True, True, [-6.0, -14.0]),
    (300, 1, True, True, [-3.0, -10.0, -2.0, 4.0]),
    (350, 2, False, True, [-2.0, -1.0, -3.0, 3.0, 6.0]),
    (250, 0, False, True, [-1.0]),
    (300, 1, True, False, [-9.0, -1.0, 2.0]),
    (300, 1, True, True, [-25.0, -25.0, -1.0, 2.0]),  # variances on their lower bounds
]


def _problem(n: int, seed: int):
    rng = np.random.default_rng(seed)
    x = np.linspace(-1.0, 1.0, n)
    X = np.column_stack([np.ones(n), x, x ** 2, x ** 3])
    y = 0.1 * rng.standard_normal(n) + 0.01 * np.cumsum(rng.standard_normal(n)) + 1e4 * x
    mask = (rng.random(n) > 0.1).astype(float)
    y[mask == 0] = np.nan  # a missing block's value must not reach the sums
    return y, X, mask, rng.uniform(0.5, 2.0, n)


@pytest.mark.parametrize("case", range(len(CASES)))
def test_values_and_gradients_equal_the_jax_definitions(case):
    n, n_markov, walk, flicker, theta = CASES[case]
    spec = ns.make_spec(4.0, 4.0 * n, n_markov=n_markov, random_walk=walk, flicker=flicker)
    theta = np.asarray(theta)
    assert spec.n_theta == theta.size
    y, X, mask, w = _problem(n, case)
    Xp, pad = ns.pad_columns(X)
    args = [jnp.asarray(a) for a in (np.where(mask > 0, y, 0.0), Xp, mask, w, pad)]
    for reml, reference in ((False, ns._negll_and_grad), (True, _negreml_and_grad)):
        v_ref, g_ref = reference(spec, jnp.asarray(theta), *args)
        v, g = nk.negloglik(spec, theta, y, X, mask, w, reml=reml)
        assert abs(v - float(v_ref)) <= 1e-9 * abs(float(v_ref))
        np.testing.assert_allclose(g, np.asarray(g_ref), rtol=1e-9,
                                   atol=1e-9 * np.abs(np.asarray(g_ref)).max())
        assert nk.negloglik(spec, theta, y, X, mask, w, reml=reml, grad=False)[0] == v


def test_system_derivatives_equal_jax_jacfwd():
    spec = ns.make_spec(2.0, 3600.0, n_markov=2)
    theta = np.array([-3.0, -9.0, -1.0, -2.5, 3.0, 5.5])

    def system(th):
        return ns.system(spec, ns.unpack(spec, th))

    ours = nk.system_and_derivatives(spec, theta)
    jac = jax.jacfwd(system)(jnp.asarray(theta))
    for value, derivative, v_ref, d_ref in zip(ours[:3], ours[3:], system(theta), jac):
        np.testing.assert_allclose(value, np.asarray(v_ref), rtol=1e-13)
        np.testing.assert_allclose(derivative, np.asarray(d_ref).T, rtol=1e-12, atol=1e-300)


def test_a_singular_design_is_a_failed_point_not_an_error():
    from fogbayes.inference.lbfgsb import failed_as_large

    spec = ns.make_spec(4.0, 1600.0)
    y, X, mask, w = _problem(400, 9)
    X = np.column_stack([X, np.zeros(len(y))])  # a column of zeros: S_XX singular
    v, g = nk.negloglik(spec, np.array([-3.0, -9.0]), y, X, mask, w)
    assert np.isnan(v) and failed_as_large(v, g)[0] == 1e300  # what L-BFGS-B is handed
