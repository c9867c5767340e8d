"""The composite compensator (:mod:`fogbayes.composite.compensate`) on the CPU: a compiled loop,
and the same generated source on whole arrays for NumPy (one-off calls, no Numba to start).

Per sample, the XLA program ``_rate``'s algorithm: scaled T', t', y = U' - c(T') - t' d(T'),
P(w) = sum_j M_j(T') w^j, clipped Halley/Newton/fixed-point steps; rate = w W_scale inside the
box with small |w P(w) - y|, else NaN. Source generated per structure (degrees, method,
iterations); coefficients are arguments, so one compilation serves every fit of that structure.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

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


def source(p, sc, box, *, method: str, iterations: int, recip,
           vectorised: bool = False) -> tuple[str, np.ndarray]:
    """(the loop's source, its coefficient vector q). The source depends on the structure
    only (degrees, method, iterations, whether a reciprocal start is used).

    ``vectorised``: the same statements on whole arrays for NumPy (no per-sample loop;
    ``np.minimum``/``np.maximum``/``np.where`` for the scalar ``min``/``max``/``if``), the
    same IEEE operations in the same order, so both backends give the same bits.
    """
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
    x, ind = ("", " " * 4) if vectorised else ("[i]", " " * 8)  # sample index, body indent
    L = ["def loop(out, U, T, t, q):"]
    L += [f"    q_{i} = q[{i}]" for i in range(len(q.values))]
    if not vectorised:
        L.append("    for i in prange(U.shape[0]):")
    L += [f"Tp = (T{x} - {T_ref}) * {T_inv}",
          f"tp = t{x} * {t_inv}",
          f"y = (U{x} - {U_ref}) * {U_inv} - {_horner(cn, 'Tp')} - tp * {_horner(dn, 'Tp')}"]
    L += [f"S{j} = {_horner(Mn[j], 'Tp')}" for j in range(k)]
    if rn is None:
        L.append("w = y / S0")
    else:
        L.append(f"w = y * {_horner(rn, 'Tp')}")
    clip = (f"w = np.minimum(np.maximum(w, {lo}), {hi})" if vectorised
            else f"w = min(max(w, {lo}), {hi})")
    if method != "paper":
        L.append(clip)
    g1 = _poly([f"{j + 1}.0 * S{j}" for j in range(k)], "w")
    g2 = _poly([f"{(j + 2) * (j + 1)}.0 * S{j + 1}" for j in range(k - 1)], "w") \
        if k > 1 else "0.0"
    for _ in range(iterations):
        if method == "paper":
            L.append(f"w = y / {_poly(S, 'w')}")
            continue
        L.append(f"g = w * {_poly(S, 'w')} - y")
        L.append(f"g1 = {g1}")
        if method == "newton":
            L.append("w = w - g / g1")
        else:
            L.append(f"g2 = {g2}")
            L.append("w = w - 2.0 * g * g1 / (2.0 * g1 * g1 - g * g2)")
        L.append(clip)
    if method == "paper":
        L.append(f"out{x or '[...]'} = w * {W_scale}")
    elif vectorised:
        L.append(f"r = np.abs(w * {_poly(S, 'w')} - y)")
        L.append(f"ok = (w > {lo}) & (w < {hi}) & (r <= {RESID_ABS!r} + {RESID_REL!r} * np.abs(y))")
        L.append(f"out[...] = np.where(ok, w * {W_scale}, np.nan)")
    else:
        L.append(f"r = abs(w * {_poly(S, 'w')} - y)")
        L.append(f"ok = (w > {lo}) and (w < {hi}) and "
                 f"(r <= {RESID_ABS!r} + {RESID_REL!r} * abs(y))")
        L.append(f"out[i] = w * {W_scale} if ok else np.nan")
    body = L[:1 + len(q.values) + (not vectorised)]
    body += [ind + line for line in L[len(body):]]
    body.append("    return out")
    return "\n".join(body) + "\n", np.asarray(q.values, dtype=float)


#: Sources whose Numba loop this process has compiled or loaded (``method="auto"`` then
#: uses it).
_COMPILED: set = set()

#: ``method="auto"``: a structure whose loop this process has not loaded yet is evaluated
#: by NumPy below this many samples. Measured on the 2-core box (paper 000's model, Halley,
#: 1e6 samples): the first loop call 0.66 s (Numba's import and CPU target, the cached
#: loop), then 2.6 ns a sample; NumPy 84 ns a sample. The crossover is ~8e6; below 2e6 a
#: one-off call costs NumPy at most ~0.17 s.
NUMPY_BELOW = 2_000_000


@lru_cache(maxsize=64)
def _compiled(text: str):
    """The compiled program of one generated source (one per structure; module doc)."""
    from ..support.numba_cache import njit_source, numba  # Numba only when a loop is used

    _COMPILED.add(text)
    return njit_source(text, "loop", {"np": np, "prange": numba.prange}, nogil=True,
                       parallel=True, error_model="numpy")


@lru_cache(maxsize=64)
def _vectorised(text: str):
    """The NumPy function of one generated vectorised source."""
    space = {"np": np}
    exec(text, space)  # noqa: S102 -- our own generated arithmetic, no input text
    return space["loop"]


class CompensationLoop:
    """``loop(out, U, T, t, method="auto")`` for one fit's coefficients (module doc): the
    compiled program is shared by every fit of the same structure.

    ``method``: ``"loop"`` (Numba), ``"numpy"``, or ``"auto"``: NumPy for a one-off call
    (fewer than :data:`NUMPY_BELOW` samples and this structure's loop not loaded yet in the
    process), the loop otherwise. Both give the same numbers (tests/test_composite_compensate.py);
    callers that compensate many chunks ask for ``"loop"``.
    """

    def __init__(self, p, sc, box, *, method: str, iterations: int, recip):
        kw = dict(method=method, iterations=iterations, recip=recip)
        self.text, self.q = source(p, sc, box, **kw)
        self.numpy_text = source(p, sc, box, vectorised=True, **kw)[0]

    @property
    def kernel(self):
        """The shared compiled program (its ``signatures``: one per dtype)."""
        return _compiled(self.text)

    def __call__(self, out, U, T, t, method: str = "auto"):
        if method not in ("auto", "loop", "numpy"):
            raise ValueError(f"method must be 'auto', 'loop' or 'numpy', not {method!r}")
        if method == "numpy" or (method == "auto" and U.shape[0] < NUMPY_BELOW
                                 and self.text not in _COMPILED):
            with np.errstate(all="ignore"):  # the loop's error_model="numpy": inf/NaN, quietly
                return _vectorised(self.numpy_text)(out, U, T, t, self.q)
        return self.kernel(out, U, T, t, self.q)


def compile_loop(p, sc, box, *, method: str, iterations: int, recip) -> CompensationLoop:
    """The compensation loop for these coefficients (see :class:`CompensationLoop`)."""
    return CompensationLoop(p, sc, box, method=method, iterations=iterations, recip=recip)
