"""Guard for the XLA CPU hang that made the jax pin in pyproject.toml necessary.

With jax/jaxlib 0.10.0-0.10.2 on CPU the jitted, vmapped posterior draw of
:func:`fogbayes.composite.bayes.fit_bayes` (Cholesky, triangular solves, a
tridiagonal scan and a batched inverse over 1000 draws) never returns: one async-dispatch
worker waits in ``CpuPjRtRawLoadedExecutable::Execute`` for a result while every XLA thread
is idle (gdb, 2026-11-22). In isolation it hung on the first or second of 40 executions in
4 of 4 runs on 0.10.0 and 0.10.2, and completed 40 of 40 in 3 of 3 runs on 0.9.2.
``--xla_cpu_multi_thread_eigen=false`` and async dispatch off did not avoid it.

The check runs the same computation in a child process with a wall-clock limit, so a hang
fails this test with a clear message instead of stalling the suite.
"""

import subprocess
import sys
import textwrap

CHILD = textwrap.dedent("""
    import jax, jax.numpy as jnp, numpy as np
    jax.config.update("jax_enable_x64", True)
    from fogbayes.composite.cells import rate_data
    from fogbayes.composite import bayes as cb
    from fogbayes.composite.fit import _xy, default_scaling
    from fogbayes.composite.model import PAPER_ORDERS
    from fogbayes.simulate.scenarios import simulate

    data = rate_data(simulate("paper000", seed=11, dwell=20.0).recording, smooth_s=5.0)[0]
    sc = default_scaling(data)
    X, y = _xy(data, PAPER_ORDERS, sc)
    K = int(data.cell.max()) + 1
    d = cb.cell_data(X, y, data.cell, np.asarray(data.time, float), K, 0)
    rng = np.random.default_rng(0)
    n = 1000
    eta = {"sigma": jnp.asarray(0.01 * np.exp(0.02 * rng.standard_normal(n))),
           "log_lam": jnp.asarray(-4 + 0.5 * rng.standard_normal(n)),
           "rho": jnp.asarray(0.5 + 0.1 * rng.standard_normal(n))}

    def draw(e, key, d):
        G, h, _, _ = cb._suff("cells", e, d)
        cf, m = cb._conditional(G, h, e["sigma"] ** 2, 10.0)
        theta = m + jax.scipy.linalg.solve_triangular(
            cf.T, jax.random.normal(key, m.shape), lower=False)
        return theta, cb._pointwise("cells", e, theta, d, K)

    f = jax.jit(jax.vmap(draw, in_axes=(0, 0, None)))
    keys = jax.random.split(jax.random.PRNGKey(1), n)
    for _ in range(3):  # the hang came on the first or second execution (docstring)
        out = jax.block_until_ready(f(eta, keys, d))
    assert np.all(np.isfinite(np.asarray(out[1])))
    print("ok")
""")


def test_vmapped_posterior_draw_returns():
    try:
        res = subprocess.run([sys.executable, "-c", CHILD], capture_output=True, text=True,
                             timeout=240)  # ~15 s unloaded; 240 s leaves room on a busy box
    except subprocess.TimeoutExpired:
        import jax

        raise AssertionError(f"the vmapped posterior draw hung on jax {jax.__version__} "
                             "(see this module's docstring; keep jax < 0.10)") from None
    assert res.returncode == 0 and res.stdout.strip().endswith("ok"), res.stderr[-2000:]
