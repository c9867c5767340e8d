"""A wide whitening runs through a bounded program, a chunk of columns at a time, with the
values of the one wide pass.

The columns of :func:`fogbayes.inference.noise_ssm.whiten_raw` share the Kalman gains and
are filtered independently, so splitting them changes no value; what it changes is the
memory: a screening of thousands of candidate columns held several (blocks x 4096) copies
(the padded input, its device copy, the masked input, the innovations) at once. The
reference is that one wide pass, called directly.
"""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np

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
    raw = ns.whiten_raw

    def spy(spec_, th, Yj, m, w_):
        widths.append(Yj.shape[1])
        return raw(spec_, th, Yj, m, w_)

    monkeypatch.setattr(ns, "whiten_raw", spy)
    V, F = ns.filter_padded(spec, theta, Y, mask, w)
    assert max(widths) <= ns.MAX_FILTER_COLUMNS and len(widths) == 3

    Yp = np.zeros((n, 4 ** int(np.ceil(np.log(c) / np.log(4)))))  # the one wide pass
    Yp[:, :c] = Y
    V1, F1 = raw(spec, jnp.asarray(theta, dtype=float), jnp.asarray(Yp), jnp.asarray(mask),
                 jnp.asarray(w))
    assert V.shape == (n, c)
    np.testing.assert_array_equal(V, np.asarray(V1)[:, :c])
    np.testing.assert_array_equal(F, np.asarray(F1))

    W, _ = ns.whiten(spec, theta, Y, mask, w)  # scaled in place: the same as a scaled copy
    scale = (mask / np.sqrt(np.asarray(F1)))[:, None]
    np.testing.assert_array_equal(W, np.asarray(V1)[:, :c] * scale)


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
