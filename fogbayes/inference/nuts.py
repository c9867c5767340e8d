"""One NUTS driver for every posterior fogbayes samples (NumPyro's functional ``hmc`` API).

A function of (keys, starts, *data) that warms up and samples several chains: data are
arguments, so same shapes reuse the compilation; ``num_warmup + num_samples`` steps in one
``lax.scan``, keeping the last ``num_samples`` draws and divergences.
"""

from __future__ import annotations

import jax

from ..support.lazy import host_device
from ..support.programs import program


def chain_sampler(potential_fn_gen, num_warmup: int, num_samples: int, *,
                  target_accept_prob: float = 0.8, dense_mass=True,
                  chain_method: str = "vectorized", postprocess=None, on_trace=None,
                  jit: bool = True, laplace_mass: bool = True, store_key: tuple | None = None,
                  compiler_options: dict | None = None, warm_start: bool = False,
                  adapt_step_size: bool = True, return_adaptation: bool = False):
    """``f(keys (C,), z0 (C, ...), *args) -> (draws (C, num_samples, ...), divergences)``.

    ``potential_fn_gen(*args)`` returns the negative log density of the unconstrained
    parameters ``z``. ``dense_mass``: passed to NumPyro's ``init_kernel`` (True: one dense
    matrix; False: diagonal; ``[]``: a diagonal per site, what ``NUTS(model)`` uses).
    ``chain_method``: "vectorized" (chains vmapped), "sequential" (``lax.map``: on the
    CPU it compiles in ~60 % of a vmap's time and runs no slower) or "threads" (one chain's
    program, the chains run side by side in threads, one per core: XLA runs each call on one
    core and JAX's asynchronous dispatch does not overlap two calls, so on a 2-core box two
    chains can take the time of one; the draws are those of "sequential"; the Allan and pool
    posteriors use it, benchmarks/RESULTS_interactive.md). ``postprocess(z, *args)``
    maps each draw (e.g. to constrained values). ``on_trace`` is called each time JAX traces
    a chain (a way for tests to count compilations). ``jit=False`` returns the function
    unjitted, to be traced inside a caller's own jit. ``laplace_mass``: the warm-up starts
    from :func:`laplace_inverse_mass` at each chain's start instead of the identity (False:
    NumPyro's identity). ``store_key`` (threads only): a tuple naming what
    ``potential_fn_gen`` and ``postprocess`` compute; the chain's program is then kept on
    disk once traced (:func:`fogbayes.support.stored.stored`), so that a new process skips
    tracing it. ``compiler_options``: XLA's, for the chains' program (``jax.jit``'s argument;
    None: XLA's defaults; the pool's: :data:`fogbayes.pool.normal.COMPILER_OPTIONS`).
    ``warm_start``: the first of ``args`` is ``(inverse_mass, step_size)``, an adaptation
    carried over from a related posterior (``return_adaptation`` of its run): the warm-up
    starts there and adapts the step size only, keeping that mass matrix (the rest of
    ``args`` go to ``potential_fn_gen``); with ``adapt_step_size=False`` it keeps the step
    size too, and the warm-up steps only carry the chains into the posterior.
    ``return_adaptation``: ``f`` also returns each chain's adapted
    ``(inverse_mass (C, d, d), step_size (C,))``.
    """
    from numpyro.infer.hmc import hmc

    if chain_method not in ("vectorized", "sequential", "threads"):
        raise ValueError(f"chain_method {chain_method!r}: use 'vectorized', 'sequential' "
                         "or 'threads'")
    if chain_method == "threads" and not jit:
        raise ValueError("chain_method 'threads' runs compiled chains: use jit=True")
    init_kernel, sample_kernel = hmc(potential_fn_gen=potential_fn_gen, algo="NUTS")

    def chain(key, z0, *args):
        if on_trace is not None:
            on_trace()
        if warm_start:
            (inverse_mass, step_size), args = args[0], args[1:]
            state = init_kernel(z0, num_warmup, step_size=step_size, dense_mass=dense_mass,
                                inverse_mass_matrix=inverse_mass, adapt_mass_matrix=False,
                                adapt_step_size=adapt_step_size,
                                target_accept_prob=target_accept_prob, model_args=args,
                                rng_key=key)
        else:
            inverse_mass = (laplace_inverse_mass(potential_fn_gen(*args), z0, dense_mass)
                            if laplace_mass else None)
            state = init_kernel(z0, num_warmup, dense_mass=dense_mass,
                                inverse_mass_matrix=inverse_mass,
                                target_accept_prob=target_accept_prob, model_args=args,
                                rng_key=key)

        def step(st, _):
            st = sample_kernel(st, model_args=args)
            return st, (st.z, st.diverging)

        # one scan over warm-up and sampling (NumPyro's kernel stops adapting after
        # num_warmup steps itself): one copy of the NUTS kernel to compile, not two
        last, (zs, div) = jax.lax.scan(step, state, None, length=num_warmup + num_samples)
        zs, div = jax.tree_util.tree_map(lambda a: a[num_warmup:], (zs, div))
        if postprocess is not None:
            zs = jax.vmap(lambda z: postprocess(z, *args))(zs)
        if return_adaptation:  # the kernel stops adapting after num_warmup: final values
            return zs, div, (last.adapt_state.inverse_mass_matrix, last.adapt_state.step_size)
        return zs, div

    def run(keys, z0, *args):
        if chain_method == "sequential":
            return jax.lax.map(lambda kz: chain(kz[0], kz[1], *args), (keys, z0))
        return jax.vmap(chain, in_axes=(0, 0) + (None,) * len(args))(keys, z0, *args)

    if chain_method == "threads":  # the device choice is per thread: made in each
        if store_key is None:
            return in_threads(on_host(program(chain, compiler_options=compiler_options)))
        from ..support.stored import stored

        key = (store_key, num_warmup, num_samples, target_accept_prob, repr(dense_mass),
               laplace_mass, warm_start, return_adaptation) + (
            () if adapt_step_size else ("fixed step",))
        return in_threads(on_host(stored(chain, key, compiler_options=compiler_options)))
    return on_host(program(run, compiler_options=compiler_options)) if jit else run


#: curvatures below this (per unit of the unconstrained parameter) are not trusted: such
#: directions start at unit inverse mass, NumPyro's default
MIN_CURVATURE = 1e-2


def laplace_inverse_mass(potential, z0, dense_mass=True):
    """Inverse Hessian of ``potential`` at ``z0`` (raveled as NumPyro ravels ``z``), the
    warm-up's starting inverse mass matrix: the Laplace approximation of the posterior's
    covariance.

    With the identity, NumPyro's first ~175 warm-up iterations (before the first slow window
    adapts the mass) run at the step size of the stiffest direction: for the Allan posterior,
    whose log N is known to 0.6 % and an absent term's log to ~1, trees ~300 steps deep, 75 %
    of all gradient evaluations. Eigenvalues below MIN_CURVATURE (a start off the mode, a
    flat direction) are replaced by 1. Dense: the matrix; otherwise its diagonal (the
    marginal variances), as one block over every site.
    """
    import jax.numpy as jnp
    from jax.flatten_util import ravel_pytree

    flat, unravel = ravel_pytree(getattr(z0, "z", z0))  # a ParamInfo's position, or z itself
    grad = jax.grad(lambda f: potential(unravel(f)))
    # one Hessian column per step (forward over reverse in a lax.map): the same numbers as
    # jax.hessian, whose vmap over the basis compiled the thermal AR posterior ~20 s slower
    hess = jax.lax.map(lambda e: jax.jvp(grad, (flat,), (e,))[1], jnp.eye(flat.size))
    lam, vec = jnp.linalg.eigh(0.5 * (hess + hess.T))
    ok = jnp.isfinite(lam) & (lam > MIN_CURVATURE)
    inv = (vec * jnp.where(ok, 1.0 / jnp.where(ok, lam, 1.0), 1.0)) @ vec.T
    inv = jnp.where(jnp.all(jnp.isfinite(inv)), inv, jnp.eye(flat.size))
    return inv if dense_mass is True else jnp.diag(inv)


def in_threads(one_chain):
    """``f(keys (C,), z0 (C, ...), *args)`` calling ``one_chain(key, z0, *args)`` once per
    chain in a pool of threads (at most one per core), the outputs stacked along axis 0.
    XLA releases the GIL while a call runs, so the chains use the cores side by side."""
    import os
    from concurrent.futures import ThreadPoolExecutor

    import numpy as np

    def host(a):
        # each chain's slice taken in NumPy: slicing a JAX array is an eager operation,
        # a program traced and compiled in every new process (typed keys stay as they are)
        a_dtype = getattr(a, "dtype", None)
        if a_dtype is not None and jax.dtypes.issubdtype(a_dtype, jax.dtypes.prng_key):
            return a
        return np.asarray(a)

    def run(keys, z0, *args):
        n = len(keys)
        keys = host(keys)
        starts = [jax.tree_util.tree_map(lambda a, i=i: host(a)[i], z0) for i in range(n)]

        def one(i):
            return jax.block_until_ready(one_chain(keys[i], starts[i], *args))

        workers = max(1, min(n, os.cpu_count() or 1))
        if workers == 1:
            outs = [one(i) for i in range(n)]
        else:
            with ThreadPoolExecutor(workers, thread_name_prefix="fogbayes-chain") as pool:
                outs = list(pool.map(one, range(n)))
        return jax.tree_util.tree_map(lambda *xs: np.stack([np.asarray(x) for x in xs]),
                                      *outs)

    return run


def on_host(compiled):
    """``compiled`` called on the CPU device (:func:`fogbayes.support.lazy.host_device`): NUTS
    steps are small and sequential, and on an H100 machine the posteriors ran 2.6-3.1x
    slower on the GPU than on its CPU (benchmarks/RESULTS_gpu.md)."""

    def call(*args):
        with host_device():
            return compiled(*args)

    return call
