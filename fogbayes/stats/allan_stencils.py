"""The Allan-family estimators' stencils and term counts (shared by every implementation).

Each stencil estimator sums K block sums per term (K = 2: Allan, K = 3: Hadamard) with a
normalisation and is overlapping (every start) or not (starts every m samples); the modified
Allan variance ("mdev") has its own count. No JAX here: the NumPy/Numba paths import it
without starting JAX.
"""

from __future__ import annotations

import numpy as np

#: kind -> (number of block sums per term K, normalisation, overlapping)
STENCILS = {
    "oadev": (2, 2.0, True),
    "adev": (2, 2.0, False),
    "ohdev": (3, 6.0, True),
    "hdev": (3, 6.0, False),
}
KINDS = (*STENCILS, "mdev")


def static_counts(n: int, ms: tuple[int, ...], kind: str) -> np.ndarray:
    """Number of terms per m without gaps (for the EDF and the normalisation)."""
    if kind == "mdev":
        return np.array([n + 2 - 3 * m for m in ms], dtype=float)
    k, _, overlap = STENCILS[kind]
    length = np.array([n + 1 - k * m for m in ms])
    return (length if overlap else (length - 1) // np.array(ms) + 1).astype(float)
