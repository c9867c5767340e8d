"""Numerical configuration applied when fogbayes is imported.

fogbayes fits in float64: the papers' coefficients span 1e1 ... 1e-12 and Allan variances
span many decades, so single precision loses the answer. Importing fogbayes therefore turns
on JAX's 64-bit mode (``jax_enable_x64``), the same switch as ``JAX_ENABLE_X64=1`` or
``numpyro.enable_x64()``. Arrays created with an explicit ``dtype=jnp.float32`` stay
float32, which is how the compensators run in single precision when asked.

JAX is not imported here (0.5 s): ``fogbayes --help`` and commands that fit nothing do
not need it. If JAX is already imported the switch is flipped now; otherwise the
environment variable is set, which JAX reads when it is first imported. Child processes
inherit that variable: JAX programs they run are float64 too (as fogbayes' own Dask
workers need).
"""

import os
import sys

if "jax" in sys.modules:
    sys.modules["jax"].config.update("jax_enable_x64", True)
else:
    os.environ["JAX_ENABLE_X64"] = "1"
