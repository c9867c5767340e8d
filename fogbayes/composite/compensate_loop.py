"""The composite compensator (:mod:`fogbayes.composite.compensate`) as a compiled CPU loop.

Per sample, the XLA program ``_rate``'s algorithm: scaled T', t', y = U' - c(T') - t' d(T'),
P(w) = sum_j M_j(T') w^j, clipped Halley/Newton/fixed-point steps; rate = w W_scale inside the
box with small |w P(w) - y|, else NaN. Source generated per structure (degrees, method,
iterations); coefficients are arguments, so one compilation serves every fit of that structure.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from ..support.numba_cache import njit_source, numba
from .model import RESID_ABS, RESID_REL


def _horner(names: list[str], x: str) -> str:
    """``c0 + x * (c1 + x * (...))`` over the coefficients' variable names."""
    expr = names[-1]
    for c in names[-2::-1]:
        expr = f"({expr} * {x} + {c})"
    return expr


class _Names:
    """Hands out the next slot of ``q``: each coefficient becomes ``q_<i>`` (module doc)."""

    def __init__(self):
        self.values: list[float] = []

    def __call__(self, values) -> list[str]:
        start = len(self.values)
        self.values.extend(float(v) for v in np.ravel(values))
        return [f"q_{i}" for i in range(start, len(self.values))]


def _poly(terms: list[str], w: str) -> str:
    """Horner in ``w`` over per-sample coefficient expressions (the XLA ``_poly`` order)."""
    expr = terms[-1]
    for c in terms[-2::-1]:
        expr = f"({expr} * {w} + {c})"
    return expr


def source(p, sc, box, *, method: str, iterations: int, recip) -> tuple[str, np.ndarray]:
    """(the loop's source, its coefficient vector q). The source depends on the structure
    only (degrees, method, iterations, whether a reciprocal start is used)."""
    M, c, d = (np.asarray(v, dtype=float) for v in p)
    k = M.shape[1]
    q = _Names()
    lo, hi = q([box[0], box[1]])
    T_ref, T_inv, t_inv, U_ref, U_inv, W_scale = q(
        [sc.T_ref, 1.0 / sc.T_scale, 1.0 / sc.t_scale, sc.U_ref, 1.0 / sc.U_scale, sc.W_scale])
    cn, dn = q(c), q(d)
    Mn = [q(M[:, j]) for j in range(k)]
    rn = None if method == "paper" or recip is None else q(recip)
    S = [f"S{j}" for j in range(k)]
    L = ["def loop(out, U, T, t, q):"]
    L += [f"    q_{i} = q[{i}]" for i in range(len(q.values))]
    L += ["    for i in prange(U.shape[0]):",
          f"        Tp = (T[i] - {T_ref}) * {T_inv}",
          f"        tp = t[i] * {t_inv}",
          f"        y = (U[i] - {U_ref}) * {U_inv} - {_horner(cn, 'Tp')} - tp * {_horner(dn, 'Tp')}"]
    L += [f"        S{j} = {_horner(Mn[j], 'Tp')}" for j in range(k)]
    if rn is None:
        L.append("        w = y / S0")
    else:
        L.append(f"        w = y * {_horner(rn, 'Tp')}")
    clip = f"        w = min(max(w, {lo}), {hi})"
    if method != "paper":
        L.append(clip)
    g1 = _poly([f"{j + 1}.0 * S{j}" for j in range(k)], "w")
    g2 = _poly([f"{(j + 2) * (j + 1)}.0 * S{j + 1}" for j in range(k - 1)], "w") \
        if k > 1 else "0.0"
    for _ in range(iterations):
        if method == "paper":
            L.append(f"        w = y / {_poly(S, 'w')}")
            continue
        L.append(f"        g = w * {_poly(S, 'w')} - y")
        L.append(f"        g1 = {g1}")
        if method == "newton":
            L.append("        w = w - g / g1")
        else:
            L.append(f"        g2 = {g2}")
            L.append("        w = w - 2.0 * g * g1 / (2.0 * g1 * g1 - g * g2)")
        L.append(clip)
    if method == "paper":
        L.append(f"        out[i] = w * {W_scale}")
    else:
        L.append(f"        r = abs(w * {_poly(S, 'w')} - y)")
        L.append(f"        ok = (w > {lo}) and (w < {hi}) and "
                 f"(r <= {RESID_ABS!r} + {RESID_REL!r} * abs(y))")
        L.append(f"        out[i] = w * {W_scale} if ok else np.nan")
    L.append("    return out")
    return "\n".join(L) + "\n", np.asarray(q.values, dtype=float)


@lru_cache(maxsize=64)
def _compiled(text: str):
    """The compiled program of one generated source (one per structure; module doc)."""
    return njit_source(text, "loop", {"np": np, "prange": numba.prange}, nogil=True,
                       parallel=True, error_model="numpy")


def compile_loop(p, sc, box, *, method: str, iterations: int, recip):
    """``loop(out, U, T, t)`` for these coefficients (see the module doc); the compiled
    program is shared by every fit of the same structure."""
    text, q = source(p, sc, box, method=method, iterations=iterations, recip=recip)
    kernel = _compiled(text)

    def loop(out, U, T, t):
        return kernel(out, U, T, t, q)

    loop.kernel = kernel  # the shared compiled program (its ``signatures``: one per dtype)
    return loop
