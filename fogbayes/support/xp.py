"""One implementation, two array backends: NumPy for direct calls, JAX under jit/grad/vmap.

A function written with ``xp = namespace(*args)`` runs eagerly in NumPy on NumPy input (no
compilation: a small fit that would otherwise compile one XLA program per operation) and in
JAX when any argument is a JAX array or tracer (inside a NumPyro model, ``jax.grad``,
``vmap``).
"""

from __future__ import annotations

import numpy as np


def _is_jax(x) -> bool:
    if isinstance(x, (tuple, list)):
        return any(_is_jax(v) for v in x)
    return type(x).__module__.startswith(("jax", "jaxlib"))


def namespace(*xs):
    """``jax.numpy`` if any of ``xs`` (or an element of a tuple among them) is a JAX array
    or tracer, else ``numpy``."""
    if any(_is_jax(x) for x in xs):
        import jax.numpy as jnp

        return jnp
    return np


def special(xp):
    """``scipy.special`` for NumPy, ``jax.scipy.special`` for JAX."""
    if xp is np:
        import scipy.special as sp

        return sp
    import jax.scipy.special as jsp

    return jsp
