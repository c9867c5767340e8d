"""One NUTS driver for potentials written by hand: warm-up and sampling of several chains as
one jitted, chain-vmapped function (NumPyro's functional ``hmc`` API).

The data are arguments of the compiled function, not constants, so another data set of the
same shapes reuses the compilation; callers cache the returned function per sampler size.
"""

from __future__ import annotations

import jax


def chain_sampler(potential_fn_gen, num_warmup: int, num_samples: int, *,
                  target_accept_prob: float, on_trace=None):
    """``f(keys (C,), z0 (C, ...), *args) -> (draws (C, num_samples, ...), divergences)``.

    ``potential_fn_gen(*args)`` returns the negative log density of the unconstrained
    parameters ``z``; ``on_trace`` (optional) is called each time JAX traces a chain (a way
    for tests to count compilations). Dense mass matrix, adapted during warm-up.
    """
    from numpyro.infer.hmc import hmc

    init_kernel, sample_kernel = hmc(potential_fn_gen=potential_fn_gen, algo="NUTS")

    def chain(key, z0, *args):
        if on_trace is not None:
            on_trace()
        state = init_kernel(z0, num_warmup, dense_mass=True,
                            target_accept_prob=target_accept_prob, model_args=args,
                            rng_key=key)

        def step(st, _):
            st = sample_kernel(st, model_args=args)
            return st, (st.z, st.diverging)

        _, (zs, div) = jax.lax.scan(step, state, None, length=num_warmup + num_samples)
        return jax.tree.map(lambda a: a[num_warmup:], zs), div[num_warmup:]

    def run(keys, z0, *args):
        return jax.vmap(chain, in_axes=(0, 0) + (None,) * len(args))(keys, z0, *args)

    return jax.jit(run)
