"""Screening statistics of a grid wider than one chunk (fogbayes.loop.evidence._grid_stats).

One-column grid points go through the matrix products :data:`GRID_CHUNK` at a time (a step's
grid on a long record has thousands: the whole grid held four copies of (blocks x grid) at
once). Reference, per grid point: u = P z / |P z| with P the projection off the design,
stat = (u'r)^2 / s2 for the data and (u'e_b)^2 / s2_b for each simulation; a column inside
the design is not identifiable (NaN); a two-column point is the sum over an orthonormal
basis of its projected columns.
"""

from __future__ import annotations

import numpy as np

from fogbayes.loop import evidence as ev


def test_grid_wider_than_a_chunk_matches_the_per_point_formula():
    rng = np.random.default_rng(4)
    n, p, B = 300, 3, 20
    Qx, _ = np.linalg.qr(rng.standard_normal((n, p)))
    r = rng.standard_normal(n)
    r -= Qx @ (Qx.T @ r)
    E = rng.standard_normal((n, B))
    E -= Qx @ (Qx.T @ E)
    dof = n - p
    wm = ev.Whitened(None, None, Qx, r, float(r @ r / dof), E, np.sum(E * E, axis=0) / dof)
    G = 2 * ev.GRID_CHUNK + 11
    ks = [1] * G
    ks[5] = 2  # a two-column point between one-column ones
    Zw = rng.standard_normal((n, sum(ks)))
    starts = np.concatenate([[0], np.cumsum(ks)[:-1]])
    bad = ev.GRID_CHUNK + 3  # a one-column point in the second chunk lies in the design
    Zw[:, starts[bad]] = Qx @ np.array([1.0, -2.0, 0.5])

    obs, sims = ev._grid_stats(wm, Zw, ks)

    P = np.eye(n) - Qx @ Qx.T
    for g in range(G):
        Z = P @ Zw[:, starts[g]:starts[g] + ks[g]]
        if g == bad:
            assert np.isnan(obs[g]) and np.all(np.isnan(sims[g]))
            continue
        Q, _ = np.linalg.qr(Z)
        np.testing.assert_allclose(obs[g], np.sum((Q.T @ r) ** 2) / wm.s2, rtol=1e-9)
        np.testing.assert_allclose(sims[g], np.sum((Q.T @ E) ** 2, axis=0) / wm.e_s2,
                                   rtol=1e-9)
