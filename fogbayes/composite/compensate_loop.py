"""The composite compensator (:mod:`fogbayes.composite.compensate`) as a compiled CPU loop.

Per sample, the same algorithm as the XLA program ``_rate`` (scaled units)::

    T' = (T - T_ref) / T_scale,  t' = t / t_scale
    y  = (U - U_ref) / U_scale - c(T') - t' d(T')          (Horner in T')
    S_j = M_j(T'),  P(w) = sum_j S_j w^j                    (Horner in w)
    w0 = y r(T')  (r ~ 1 / S_0; y / S_0 for the paper's scheme), clipped to the box
    w <- Halley / Newton / fixed-point steps, each clipped (a fixed count)
    rate = w W_scale if w is strictly inside the box and |w P(w) - y| is small, else NaN

The coefficients are written into the generated source as constants (as the XLA program
bakes them in), so the per-sample code is straight-line and the compiler vectorises the
loop over samples (split over the cores); it reads U, T, t once and writes the rate once, into ``out`` when given.
Compiled once per compensator (a fit), ~0.3 s.
"""

from __future__ import annotations

from .._numba import numba
import numpy as np

from .model import RESID_ABS, RESID_REL


def _horner(coefs, x: str) -> str:
    """``c0 + x * (c1 + x * (...))`` with the coefficients as literals."""
    expr = repr(float(coefs[-1]))
    for c in coefs[-2::-1]:
        expr = f"({expr} * {x} + {float(c)!r})"
    return expr


def _poly(terms: list[str], w: str) -> str:
    """Horner in ``w`` over per-sample coefficient expressions (the XLA ``_poly`` order)."""
    expr = terms[-1]
    for c in terms[-2::-1]:
        expr = f"({expr} * {w} + {c})"
    return expr


def source(p, sc, box, *, method: str, iterations: int, recip) -> str:
    M, c, d = (np.asarray(v, dtype=float) for v in p)
    k = M.shape[1]
    lo, hi = (repr(float(v)) for v in box)
    S = [f"S{j}" for j in range(k)]
    L = ["def loop(out, U, T, t):", "    for i in prange(U.shape[0]):",
         f"        Tp = (T[i] - {float(sc.T_ref)!r}) * {1.0 / sc.T_scale!r}",
         f"        tp = t[i] * {1.0 / sc.t_scale!r}",
         (f"        y = (U[i] - {float(sc.U_ref)!r}) * {1.0 / sc.U_scale!r} - "
          f"{_horner(c, 'Tp')} - tp * {_horner(d, 'Tp')}")]
    L += [f"        S{j} = {_horner(M[:, j], 'Tp')}" for j in range(k)]
    if method == "paper" or recip is None:
        L.append("        w = y / S0")
    else:
        L.append(f"        w = y * {_horner(recip, 'Tp')}")
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
        L.append(f"        out[i] = w * {float(sc.W_scale)!r}")
    else:
        L.append(f"        r = abs(w * {_poly(S, 'w')} - y)")
        L.append(f"        ok = (w > {lo}) and (w < {hi}) and "
                 f"(r <= {RESID_ABS!r} + {RESID_REL!r} * abs(y))")
        L.append(f"        out[i] = w * {float(sc.W_scale)!r} if ok else np.nan")
    L.append("    return out")
    return "\n".join(L) + "\n"


def compile_loop(p, sc, box, *, method: str, iterations: int, recip):
    """``loop(out, U, T, t)`` for these coefficients (see the module doc)."""
    space = {"np": np, "prange": numba.prange}
    exec(source(p, sc, box, method=method, iterations=iterations, recip=recip), space)  # noqa: S102
    return numba.njit(nogil=True, parallel=True, error_model="numpy")(space["loop"])
