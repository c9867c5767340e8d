"""Compiled compensation loops for polynomial bias models (Numba, CPU), one per term set.

Per sample, as :func:`fogbayes.thermal.compensate.bias_compensator`: u_c = (z_c - centre_c) / scale_c,
out = y - sum_k coef_k prod_c u_c^{e_kc}. Source generated per term set; coefficients, centre and
scale are arguments; ``out`` may be written in place. One-off calls run the same source on whole
arrays in NumPy.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from functools import lru_cache

import numpy as np


def _source(terms: tuple[tuple[int, ...], ...], vectorised: bool = False) -> str:
    """The loop's source; ``vectorised``: the same statements on whole arrays for NumPy (the
    float64 reciprocal of each scale made explicit, as Numba types ``1.0 / scale[j]``), so
    both backends give the same bits."""
    c = len(terms[0])
    lines = ["def loop(out, y, z, coef, centre, scale):"]
    one = "np.float64(1.0)" if vectorised else "1.0"
    lines += [f"    r{j} = {one} / scale[{j}]" for j in range(c)]
    if vectorised:
        x, row, ind = "", ":", "    "
    else:
        x, row, ind = "[i]", "i", "        "
        lines.append("    for i in prange(y.shape[0]):")
    lines += [f"{ind}u{j} = (z[{row}, {j}] - centre[{j}]) * r{j}" for j in range(c)]
    parts = []
    for k, e in enumerate(terms):
        factors = [f"u{j}" for j, ej in enumerate(e) for _ in range(ej)]
        parts.append(" * ".join([f"coef[{k}]", *factors]))
    lines.append(f"{ind}out{x or '[...]'} = y{x} - ({' + '.join(parts)})")
    if vectorised:
        lines.append("    return out")
    return "\n".join(lines) + "\n"


#: Numba's default threading layer (workqueue: the only one a pip install is sure to have)
#: must not be entered by two Python threads at once (numba docs, "The Threading Layers"),
#: and a caller may run compensation from its own thread pool, so launches are serialised.
#: Each launch already uses every core, so nothing is lost.
_LAUNCH = threading.Lock()


#: Term sets whose loop this process has compiled (``method="auto"`` then uses it).
_COMPILED_TERMS: set = set()


@lru_cache(maxsize=64)
def _compiled(terms: tuple[tuple[int, ...], ...]) -> Callable:
    _COMPILED_TERMS.add(terms)
    from ..support.numba_cache import njit_source, numba  # Numba only when a loop is built

    return njit_source(_source(terms), "loop", {"prange": numba.prange}, nogil=True,
                       parallel=True)


#: ``method="auto"``: a term set whose loop is not compiled yet in this process is evaluated
#: by NumPy below this many samples. Measured on the 2-core box: compiling a loop costs
#: ~0.7 s, NumPy ~55-125 ns a sample against ~4 ns for the loop: the crossover is ~6e6.
NUMPY_BELOW = 5_000_000


@lru_cache(maxsize=64)
def _vectorised(terms: tuple[tuple[int, ...], ...]) -> Callable:
    space = {"np": np}
    exec(_source(terms, vectorised=True), space)  # noqa: S102 -- our own generated arithmetic
    return space["loop"]


def compensate_numpy(basis, coef, z, y, out=None) -> np.ndarray:
    """The loop's source run on whole arrays in NumPy (no compilation), the same bits."""
    out = np.empty_like(y) if out is None else out
    return _vectorised(basis.terms)(out, y, z, coef, np.asarray(basis.centre, dtype=y.dtype),
                                    np.asarray(basis.scale, dtype=y.dtype))


def compensate_into(basis, coef, z, y, out=None, *, method: str = "auto") -> np.ndarray:
    """``y - X(z) @ coef`` of one sensor (``z`` (n, c), ``y`` (n,)) written into ``out``
    (a new array of ``y``'s dtype when None); returns ``out``.

    ``method``: ``"loop"`` (the compiled loop), ``"numpy"``, or ``"auto"``: NumPy for a
    one-off call (fewer than :data:`NUMPY_BELOW` samples and no loop compiled yet for these
    terms), the loop otherwise. Callers that compensate many chunks ask for ``"loop"``.
    """
    y = np.asarray(y)
    z = np.asarray(z, dtype=y.dtype).reshape(y.shape[0], -1)
    coef = np.asarray(coef, dtype=y.dtype)
    if method not in ("auto", "loop", "numpy"):
        raise ValueError(f"method must be 'auto', 'loop' or 'numpy', not {method!r}")
    one_off = y.shape[0] < NUMPY_BELOW and basis.terms not in _COMPILED_TERMS
    if method == "numpy" or (method == "auto" and one_off):
        return compensate_numpy(basis, coef, z, y, out)
    out = np.empty_like(y) if out is None else out
    kernel = _compiled(basis.terms)
    with _LAUNCH:
        kernel(out, y, z, coef, np.asarray(basis.centre, dtype=y.dtype),
               np.asarray(basis.scale, dtype=y.dtype))
    return out
