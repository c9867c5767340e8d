"""A wide whitening runs a chunk of columns at a time, with the values of the one wide pass.

The columns of the filter share the Kalman gains and are filtered independently, so
splitting them changes no value; what it bounds is the memory: a screening of thousands of
candidate columns would hold a masked copy of them all. The reference is one wide pass of
:func:`fogbayes.inference.noise_ssm.whiten_raw` (the JAX definition of the filter), called
directly: the CPU filter's values agree with it to rounding.
"""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np

from fogbayes.inference import noise_kalman as nk
from fogbayes.inference import noise_ssm as ns


def test_wide_filter_runs_in_chunks_with_the_values_of_one_pass(monkeypatch):
    rng = np.random.default_rng(3)
    n, dt = 600, 2.0
    spec = ns.make_spec(dt, n * dt)
    theta = np.array([-2.0, -9.0])[:spec.n_theta]
    mask = np.ones(n)
    mask[rng.choice(n, 40, replace=False)] = 0.0  # missing blocks
    w = rng.uniform(0.8, 1.2, n)
    c = 2 * ns.MAX_FILTER_COLUMNS + 37  # two full chunks and a padded remainder
    Y = rng.standard_normal((n, c)) + np.cumsum(rng.standard_normal((n, c)), axis=0)

    widths = []
    one = nk.innovations

    def spy(spec_, th, Yj, m, w_, grad=True):
        widths.append(Yj.shape[1])
        return one(spec_, th, Yj, m, w_, grad)

    monkeypatch.setattr(nk, "innovations", spy)
    V, F = ns.filter_padded(spec, theta, Y, mask, w)
    assert max(widths) <= ns.MAX_FILTER_COLUMNS and len(widths) == 3
    raw = ns.whiten_raw

    Yp = np.zeros((n, 4 ** int(np.ceil(np.log(c) / np.log(4)))))  # the one wide pass
    Yp[:, :c] = Y
    V1, F1 = raw(spec, jnp.asarray(theta, dtype=float), jnp.asarray(Yp), jnp.asarray(mask),
                 jnp.asarray(w))
    assert V.shape == (n, c)
    scale = np.abs(np.asarray(V1)).max()  # innovations of a walk: relative to the largest
    np.testing.assert_allclose(V, np.asarray(V1)[:, :c], rtol=0, atol=1e-11 * scale)
    np.testing.assert_allclose(F, np.asarray(F1), rtol=1e-12)

    W, F2 = ns.whiten(spec, theta, Y, mask, w)  # scaled in place: the same as a scaled copy
    np.testing.assert_array_equal(W, V * (mask / np.sqrt(F2))[:, None])


def test_blocks_side_by_side_whiten_as_their_stack():
    rng = np.random.default_rng(8)
    n = 400
    spec = ns.make_spec(2.0, n * 2.0)
    theta = np.array([-1.5, -8.0])[:spec.n_theta]
    mask, w = np.ones(n), np.ones(n)
    mask[::37] = 0.0
    blocks = [rng.standard_normal((n, k)) for k in (1, 5, 0, ns.MAX_FILTER_COLUMNS + 3, 40)]
    W_list, F_list = ns.whiten(spec, theta, blocks, mask, w)  # chunks cross the block edges
    W_stack, F_stack = ns.whiten(spec, theta, np.column_stack(blocks), mask, w)
    np.testing.assert_array_equal(W_list, W_stack)
    np.testing.assert_array_equal(F_list, F_stack)
    small = blocks[:2]  # one program call, below the chunk width
    np.testing.assert_array_equal(ns.whiten(spec, theta, small, mask, w)[0],
                                  ns.whiten(spec, theta, np.column_stack(small), mask, w)[0])
