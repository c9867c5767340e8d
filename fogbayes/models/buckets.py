"""Array lengths compiled programs are built for: n samples are held in ``bucket_length(n)``.

The tail is masked out, so records of nearby lengths share one program (at most a quarter
more work per evaluation).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np


def bucket_length(n: int) -> int:
    """n rounded up to a multiple of 2^(floor(log2 n) - 2): four lengths per octave, at
    most 25 % of padding (lengths below 8 are kept)."""
    step = 1 << max(int(n).bit_length() - 3, 0)
    return -(-int(n) // step) * step


def padded(x, n_to: int):
    """x (..., n) with zeros appended along the last axis to n_to samples (NumPy for a
    concrete array, jnp.pad for a traced one)."""
    pad = [(0, 0)] * (jnp.ndim(x) - 1) + [(0, n_to - jnp.shape(x)[-1])]
    if isinstance(x, jax.core.Tracer):
        return jnp.pad(jnp.asarray(x, dtype=float), pad)
    return np.pad(np.asarray(x, dtype=float), pad)


def held(x):
    """(x padded to ``bucket_length`` of its last axis, that axis' length n): the one rule
    by which every bucketed caller holds its series."""
    n = jnp.shape(x)[-1]
    return padded(x, bucket_length(n)), n
