"""What the memory-map bound of fogbayes.support.programs costs a call, as ratios in one run.

    python benchmarks/bench_programs.py

1. A warm call of a tiny program through ``program`` against the same function through
   ``jax.jit`` (the wrapper's two cache-size reads are the whole difference).
2. A warm ``compensate_sensors`` call (composite family, 16 sensors x 4 096 samples)
   through ``program`` against its own ``jax.jit`` function (and a copy of U, for scale).
3. What dropping fogbayes's programs gives back: maps held after an ARMA fit and after
   ``release_programs()``, against ``jax.clear_caches()``.
4. The thermal XLA batch compensator (the fleet and GPU path) with the basis's centre and
   scale as arguments (one program per term set, as fogbayes runs it) against the same
   function with them baked in as constants (the other design: one program per
   calibration), and a copy of y for scale.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from _timing import best_of  # noqa: E402

import fogbayes  # noqa: E402, F401  (float64, before JAX)
import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402

from fogbayes.support import programs  # noqa: E402


def call_overhead(calls: int = 20_000, repeat: int = 7) -> None:
    def f(v):
        return v * 2.0

    jitted, prog = jax.jit(f), programs.program(f)
    x = jnp.ones(8)
    for g in (jitted, prog):
        g(x).block_until_ready()

    def many(g):
        def run():
            for _ in range(calls):
                g(x)
            g(x).block_until_ready()
        return run

    t_jit = best_of(many(jitted), repeat) / calls
    t_prog = best_of(many(prog), repeat) / calls
    print(f"tiny call: jax.jit {t_jit * 1e6:.2f} us, program {t_prog * 1e6:.2f} us "
          f"(ratio {t_prog / t_jit:.3f}, +{(t_prog - t_jit) * 1e6:.2f} us)")


def compensate_sensors_call(k: int = 16, n: int = 4096, repeat: int = 20) -> None:
    from fogbayes.composite.compensate import compensate_sensors, monotone_box
    from fogbayes.composite.model import PAPER_000, Scaling, from_raw, raw_predict

    rng = np.random.default_rng(0)
    T, W, t = rng.uniform(-30, 60, (k, n)), rng.uniform(-80, 80, (k, n)), rng.uniform(0, 60, (k, n))
    U = raw_predict(PAPER_000, T, W, t)
    sc = Scaling(15.0, 45.0, 80.0, 60.0, float(U.mean()), float(np.abs(U - U.mean()).max()))
    p = from_raw(PAPER_000, sc)
    box = monotone_box(p, (-30, 60), sc)
    stack = jax.tree_util.tree_map(lambda a: jnp.broadcast_to(jnp.asarray(a), (k,) + jnp.shape(a)), p)
    scs = Scaling(*(jnp.full(k, v) for v in sc))
    boxes = jnp.array([box] * k)
    args = (stack, scs, boxes, jnp.asarray(U), jnp.asarray(T), jnp.asarray(t))

    def run(f):
        return lambda: f(*args).rate.block_until_ready()

    run(compensate_sensors)()
    src = np.asarray(U)
    dst = np.empty_like(src)
    t_call = best_of(run(compensate_sensors), repeat)
    t_raw = best_of(run(compensate_sensors.jitted), repeat)  # the same program, no bound
    t_copy = best_of(lambda: np.copyto(dst, src), repeat)
    print(f"compensate_sensors {k} x {n}, warm: {t_call * 1e3:.3f} ms through program, "
          f"{t_raw * 1e3:.3f} ms through its jax.jit (ratio {t_call / t_raw:.3f}); "
          f"a copy of U {t_copy * 1e3:.3f} ms")


def maps_given_back() -> None:
    from fogbayes.arma.fit import fit_arma

    x = np.random.default_rng(1).standard_normal(3000)
    before = programs.memory_maps()
    fit_arma(x, p=2, q=1).loglik.block_until_ready()
    held = programs.memory_maps()
    programs.release_programs()
    ours = programs.memory_maps()
    fit_arma(x, p=2, q=1).loglik.block_until_ready()
    jax.clear_caches()
    everything = programs.memory_maps()
    print(f"maps: {before} at start, {held} after an ARMA(2,1) fit, {ours} after "
          f"release_programs(), {everything} after jax.clear_caches() (same fit again)")


def thermal_batch_arguments(k: int = 16, n: int = 1 << 18, repeat: int = 15) -> None:
    from fogbayes.thermal.compensate import _xla_programs

    terms = ((0, 0), (1, 0), (0, 1), (2, 0), (1, 1), (0, 2))  # thermal (2, 2) in T, dT/dt
    rng = np.random.default_rng(2)
    z = jnp.asarray(np.stack([rng.uniform(-20, 60, (k, n)), rng.uniform(-1, 1, (k, n))], -1))
    y = jnp.asarray(rng.standard_normal((k, n)))
    coef = jnp.asarray(rng.standard_normal((k, len(terms))))
    centre, scale = np.array([20.0, 0.0]), np.array([40.0, 0.5])
    single, as_args = _xla_programs(terms)
    # the library's own function with centre and scale closed over: traced as constants,
    # so XLA folds them (and 1/scale) into this program, one per calibration
    baked = jax.jit(jax.vmap(lambda c, zz, yy: single(c, zz, yy, centre, scale)))
    cz, sz = jnp.asarray(centre), jnp.asarray(scale)
    # the same sums; XLA may fold 1/scale differently: a rounding or two of each term
    assert np.allclose(as_args(coef, z, y, cz, sz), baked(coef, z, y), rtol=0, atol=1e-11)
    src = np.asarray(y)
    dst = np.empty_like(src)
    t_args = best_of(lambda: as_args(coef, z, y, cz, sz).block_until_ready(), repeat)
    t_baked = best_of(lambda: baked(coef, z, y).block_until_ready(), repeat)
    t_copy = best_of(lambda: np.copyto(dst, src), repeat)
    print(f"thermal XLA batch {k} x {n}: centre/scale as arguments {t_args * 1e3:.2f} ms, "
          f"baked in {t_baked * 1e3:.2f} ms (ratio {t_args / t_baked:.3f}); "
          f"a copy of y {t_copy * 1e3:.2f} ms")


if __name__ == "__main__":
    print(f"jax {jax.__version__}, vm.max_map_count {programs.max_map_count()}, "
          f"limit {programs.map_limit()} maps")
    call_overhead()
    compensate_sensors_call()
    maps_given_back()
    thermal_batch_arguments()
