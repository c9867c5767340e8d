"""Compensation with the composite model: solve U(W) = U_measured for the input rate W.

g(W) = W P(W) - y = 0, P(W) = sum_j S_j(T) W^j, y = U - U0(T) - U1(T) t, in scaled units, from
w0 = y / S_0(T): ``"halley"`` (default), ``"newton"``, or ``"paper"`` (paper 000's fixed point
w <- y / P(w)). A fixed iteration count (:func:`choose_iterations`); iterates clamped to the
monotone region around W = 0; no inverse gives NaN and ``in_range`` False.
"""

from __future__ import annotations

from functools import partial
from typing import NamedTuple

import numpy as np

from ..errors import FogbayesError
from ..support.lazy import jax_on_cpu, lazy_module
from ..support.programs import program
from .model import (RESID_ABS, RESID_REL, FullParams, ProductParams, Scaling, _horner,
                    product_to_full)

METHODS = ("halley", "newton", "paper")


# imported at first use: on a CPU calls go to the compiled loop (compensate_loop)
jax = lazy_module("jax")
jnp = lazy_module("jax.numpy")


class CompensationResult(NamedTuple):
    """Compensated rate (deg/s) and whether the sample lies in the invertible region."""

    rate: jnp.ndarray
    in_range: jnp.ndarray


class Compensator(NamedTuple):
    """A compensator built once per model; call it as ``comp(U, T, t)``.

    ``box`` is the monotone region in scaled rate units (lo < 0 < hi). ``fn`` is jitted
    with the coefficients baked in as constants (2-5x faster on XLA CPU than passing the
    13 coefficient and scaling arrays); it compiles once per input shape and dtype.
    """

    params: FullParams
    scaling: Scaling
    box: tuple[float, float]
    iterations: int
    method: str
    fn: object  # jitted XLA (U, T, t) -> CompensationResult, coefficients baked in
    stream_fn: object  # the XLA rate, U's buffer donated to the output
    loop: object = None  # on a CPU: loop(out, U, T, t) (:class:`.compensate_loop.CompensationLoop`)

    def __call__(self, U, T, t) -> CompensationResult:
        if self.loop is not None:
            return _loop_result(self.loop, U, T, t)
        return self.fn(U, T, t)

    def stream(self, U, T, t, out=None):
        """Rate only (NaN where not invertible): for chunked streaming of long records.

        On a CPU the compiled loop writes into ``out`` (a new array when None). Elsewhere
        the XLA program writes into U's buffer: ``U`` must be a JAX array you no longer
        need (it is donated), and ``out`` is not used."""
        if self.loop is not None:
            U = np.asarray(U)
            return self.loop(np.empty(U.shape, U.dtype) if out is None else out, U,
                             np.asarray(T, U.dtype), np.asarray(t, U.dtype), method="loop")
        return self.stream_fn(U, T, t)


class MethodError(FogbayesError):
    """An unknown compensation method or iteration count."""


# ------------------------------------------------------------------------------ the kernel
def _prepare(p: FullParams, sc: Scaling, U, T, t):
    """Per-sample S_j(T') (list) and y' = U' - B'(T', t'), in the dtype of U."""
    dt = jnp.result_type(U)
    p = jax.tree_util.tree_map(lambda a: jnp.asarray(a, dt), p)
    # one scalar reciprocal each instead of a division per sample
    Tp = (T - sc.T_ref) * (1.0 / sc.T_scale)
    tp = t * (1.0 / sc.t_scale)
    y = (U - sc.U_ref) * (1.0 / sc.U_scale) - _horner(p.c, Tp) - tp * _horner(p.d, Tp)
    S = [_horner(p.M[:, j], Tp) for j in range(p.M.shape[1])]
    return S, y


def _step(method: str, S, y, w):
    """One iteration of ``method`` for g(w) = w P(w) - y (Horner for P, P', P'')."""
    if method == "paper":
        return y / _poly(S, w)
    k = len(S)
    g = w * _poly(S, w) - y
    g1 = _poly([(j + 1) * S[j] for j in range(k)], w)  # d/dw of sum S_j w^(j+1)
    if method == "newton":
        return w - g / g1
    g2 = _poly([(j + 2) * (j + 1) * S[j + 1] for j in range(k - 1)], w) if k > 1 else 0.0 * w
    return w - 2.0 * g * g1 / (2.0 * g1 * g1 - g * g2)


def _poly(coefs, w):
    out = coefs[-1] * jnp.ones_like(w)
    for c in coefs[-2::-1]:
        out = out * w + c
    return out


def _solve(S, y, w, lo, hi, scale, *, method: str, iterations: int):
    """Iterate ``method`` on g(w) = w P(w) - y from the start ``w`` (scaled units) and
    return ``w * scale``, NaN where the output cannot be inverted. ``lo``/``hi``: the
    monotone box, scalars or one per sample. (The scale is applied inside the final
    select: applied to its result, XLA fused the vmapped program worse, 2.7x slower.)"""
    if method != "paper":
        w = jnp.clip(w, lo, hi)
    # A static, small, unrolled loop (not lax.scan) so that XLA fuses the chain into a few
    # elementwise loops.
    for _ in range(iterations):
        w = _step(method, S, y, w)
        if method != "paper":
            w = jnp.clip(w, lo, hi)
    if method == "paper":  # the baseline stops early by design: no convergence test
        return w * scale
    # Invertible: inside the monotone box and actually solved (an output the model cannot
    # produce leaves a large residual even when the iterate stayed inside the box). The
    # verdict is folded into the rate as NaN: returning a separate flag from the same
    # computation made XLA CPU 4-5x slower in every variant tried.
    resid = jnp.abs(w * _poly(S, w) - y)
    ok = (w > lo) & (w < hi) & (resid <= RESID_ABS + RESID_REL * jnp.abs(y))
    return jnp.where(ok, w * scale, jnp.nan)


def _rate(p: FullParams, sc: Scaling, box, U, T, t, *, method: str, iterations: int,
          recip=None):
    """Rate in deg/s, NaN where the output cannot be inverted (one output: see _solve).

    ``recip``: coefficients of a polynomial in T' approximating 1 / S_0(T) (see
    :func:`reciprocal_poly`); the linear starting guess then costs no division. The
    paper's scheme always divides, as printed.
    """
    S, y = _prepare(p, sc, U, T, t)
    lo, hi = jnp.asarray(box[0], y.dtype), jnp.asarray(box[1], y.dtype)
    if recip is None or method == "paper":
        w = y / S[0]
    else:
        Tp = (T - sc.T_ref) * (1.0 / sc.T_scale)
        w = y * _horner(jnp.asarray(recip, y.dtype), Tp)
    return _solve(S, y, w, lo, hi, sc.W_scale, method=method, iterations=iterations)


@partial(program, static_argnames=("method", "iterations"))
def _solve_from_linear(S, y, lo, hi, *, method: str, iterations: int):
    return _solve(list(S), y, y / S[0], lo, hi, 1.0, method=method, iterations=iterations)


def invert_polynomial(S, y, *, method: str = "halley", iterations: int = 6,
                      margin: float = 0.02, limit: float = 10.0) -> np.ndarray:
    """Solve w P(w) = y per sample, P(w) = sum_j S[:, j] w^j, with coefficients of its own
    for every sample (scaled units: y and w of order 1 at full scale).

    The same iteration as the family's :class:`Compensator` (``method``, clamped into each
    sample's monotone box :func:`monotone_bounds`, started from the linear guess y / S_0),
    for models whose coefficients depend on more than the temperature (the closed loop's
    composite calibrations). NaN where no inverse lies in the box. Compiled once per shape
    and number of coefficients: the coefficients are arguments.
    """
    S = np.asarray(S, float)
    lo, hi = monotone_bounds(S, margin=margin, limit=limit)
    w = _solve_from_linear(tuple(S.T), np.asarray(y, float), lo, hi, method=method,
                           iterations=int(iterations))
    return np.asarray(w)


def _result(p, sc, box, U, T, t, *, method, iterations, recip=None):
    rate = _rate(p, sc, box, U, T, t, method=method, iterations=iterations, recip=recip)
    return CompensationResult(rate, jnp.isfinite(rate))


@partial(program, static_argnames=("method", "iterations"))
def compensate(p: FullParams, sc: Scaling, box, U, T, t, *, method: str = "halley",
               iterations: int = 2) -> CompensationResult:
    """Compensated input rate W (deg/s) for outputs U at temperatures T and times t.

    ``rate`` is NaN (and ``in_range`` False) where U cannot be inverted. The coefficients
    are arguments here (what ``vmap`` over sensors or posterior draws needs); a
    :class:`Compensator` bakes them in and runs faster.

    Args:
        p, sc: scaled full-matrix parameters and their scaling.
        box: (lo, hi) monotone region in scaled rate units (see :func:`monotone_box`).
        U, T, t: arrays of one shape (any dtype; float32 stays float32).
        method, iterations: static; see the module docstring.
    """
    return _result(p, sc, box, U, T, t, method=method, iterations=iterations)


@partial(program, static_argnames=("method", "iterations"))
def compensate_sensors(p: FullParams, sc: Scaling, box, U, T, t, *, method: str = "halley",
                       iterations: int = 2) -> CompensationResult:
    """Many sensors at once: every argument has a leading sensor axis (k, ...).

    Compiled once per shape, dtype and (method, iterations): the coefficients are
    arguments, so new sensors reuse the program.
    """
    f = partial(_result, method=method, iterations=iterations)
    return jax.vmap(f)(p, sc, box, U, T, t)


@partial(program, static_argnames=("method", "iterations"))
def _draw_rates(p_draws: FullParams, sc: Scaling, box, U, T, t, eps, *, method: str,
                iterations: int):
    """W_s = U^-1(U - eps_s; theta_s) for every draw s (leading axis of p_draws, eps)."""
    def one(p, e):
        return _rate(p, sc, box, U - e, T, t, method=method, iterations=iterations)

    return jax.vmap(one)(p_draws, eps)


def compensate_draws(p_draws: FullParams, sc: Scaling, box, U, T, t, *, key,
                     noise_sd=None, prob: float = 0.9, method: str = "halley",
                     iterations: int = 3):
    """Posterior-predictive interval of the compensated rate.

    For each posterior draw theta_s (leading axis of ``p_draws``) and, if ``noise_sd``
    (scaled output units, one per draw) is given, a fresh output noise draw xi_s, the
    rate W_s = U^-1(U - xi_s; theta_s). Returns (median, lower, upper) of W_s per sample
    (central ``prob`` interval). Memory is draws x samples: chunk long records. The
    program is compiled once per shape: data and draws are arguments, not constants.
    """
    n_draws = p_draws.M.shape[0]
    U = jnp.asarray(U)
    if noise_sd is None:
        eps = jnp.zeros((n_draws,) + U.shape, U.dtype)
    else:
        eps = jax.random.normal(key, (n_draws,) + U.shape, U.dtype)
        eps = eps * (jnp.asarray(noise_sd, U.dtype) * sc.U_scale).reshape((-1,) + (1,) * U.ndim)
    W = _draw_rates(p_draws, sc, box, U, T, t, eps, method=method, iterations=iterations)
    # a draw that cannot invert a sample (NaN) is left out of that sample's quantiles
    q = jnp.nanquantile(W, jnp.array([0.5, (1 - prob) / 2, (1 + prob) / 2]), axis=0)
    return q[0], q[1], q[2]


# ------------------------------------------------------------------------------ build time
def monotone_bounds(S, *, margin: float = 0.02, limit: float = 10.0):
    """Per row of S (n, K): the largest (lo, hi) around 0 where d/dw [w P(w)] keeps its sign.

    The derivative sum_j (j+1) S_j w^j is a polynomial in w; its real roots nearest to 0 on
    each side (eigenvalues of the companion matrices, all rows at once) bound the
    invertible region. ``margin`` keeps a little away from the fold; ``limit`` caps it.
    """
    S = np.atleast_2d(np.asarray(S, dtype=float))
    n, k = S.shape
    lo, hi = np.full(n, -float(limit)), np.full(n, float(limit))
    if k > 1:
        der = S * (np.arange(k) + 1.0)
        size = np.maximum(np.max(np.abs(der), axis=1), 1e-300)
        lead = der[:, -1]
        # a vanishing leading coefficient (e.g. a T' factor at T = centre) stands in as a
        # tiny one: its extra root lies far outside any box, the others barely move
        tiny = 1e-12 * size
        lead = np.where(np.abs(lead) < tiny, np.where(lead < 0, -tiny, tiny), lead)
        comp = np.zeros((n, k - 1, k - 1))
        comp[:, 0, :] = -der[:, -2::-1] / lead[:, None]
        if k > 2:
            idx = np.arange(k - 2)
            comp[:, idx + 1, idx] = 1.0
        roots = np.linalg.eigvals(comp)
        real = np.abs(roots.imag) < 1e-9 * np.maximum(1.0, np.abs(roots))
        r = np.where(real, roots.real, np.nan)
        hi = np.fmin(hi, np.nanmin(np.where(r > 0, r, np.inf), axis=1))
        lo = np.fmax(lo, np.nanmax(np.where(r < 0, r, -np.inf), axis=1))
    return lo * (1 - margin), hi * (1 - margin)


def monotone_box(p: FullParams, T_range: tuple[float, float], sc: Scaling, *,
                 margin: float = 0.02, limit: float = 10.0, n_T: int = 41) -> tuple[float, float]:
    """Largest (lo, hi) around 0 in scaled rate where d/dW [W P(W)] keeps its sign at all T
    (:func:`monotone_bounds` over a grid of ``n_T`` temperatures in ``T_range``)."""
    M = np.asarray(p.M, dtype=float)
    Tp = (np.linspace(*T_range, n_T) - sc.T_ref) / sc.T_scale
    S = np.stack([np.polynomial.polynomial.polyval(Tp, M[:, j]) for j in range(M.shape[1])],
                 axis=1)
    lo, hi = monotone_bounds(S, margin=margin, limit=limit)
    return float(np.max(lo)), float(np.min(hi))


def compensate_numpy(p: FullParams, sc: Scaling, box, U, T, t, *, method: str = "halley",
                     iterations: int = 2):
    """The same algorithm in plain NumPy (float64): reference for tests and benchmarks."""
    M, c, d = (np.asarray(v, dtype=float) for v in p)
    Tp = (T - sc.T_ref) / sc.T_scale
    tp = t / sc.t_scale
    hp = lambda k, x: np.polynomial.polynomial.polyval(x, k)  # noqa: E731
    y = (U - sc.U_ref) / sc.U_scale - hp(c, Tp) - tp * hp(d, Tp)
    S = [hp(M[:, j], Tp) for j in range(M.shape[1])]
    k = len(S)
    pv = lambda cs, w: sum(cs[j] * w ** j for j in range(len(cs)))  # noqa: E731
    w = y / S[0]
    clip = (lambda w: np.clip(w, box[0], box[1])) if method != "paper" else (lambda w: w)
    w = clip(w)
    for _ in range(iterations):
        if method == "paper":
            w = y / pv(S, w)
        else:
            g = w * pv(S, w) - y
            g1 = pv([(j + 1) * S[j] for j in range(k)], w)
            if method == "newton":
                w = w - g / g1
            else:
                g2 = pv([(j + 2) * (j + 1) * S[j + 1] for j in range(k - 1)], w)
                w = w - 2 * g * g1 / (2 * g1 * g1 - g * g2)
        w = clip(w)
    if method == "paper":
        return w * sc.W_scale, np.isfinite(w)
    resid = np.abs(w * pv(S, w) - y)
    ok = (w > box[0]) & (w < box[1]) & (resid <= RESID_ABS + RESID_REL * np.abs(y))
    return np.where(ok, w * sc.W_scale, np.nan), ok


def choose_iterations(p: FullParams, sc: Scaling, box, T_range, W_range, *,
                      method: str = "halley", rtol: float = 1e-9, max_iter: int = 8) -> int:
    """Smallest fixed iteration count reaching ``rtol`` (relative) over the calibrated box.

    Runs :func:`compensate_numpy` on model-consistent outputs on a grid of temperatures
    and rates (T_range x W_range, clipped to the monotone box) and returns the first count
    whose worst relative rate error is below ``rtol``; raises if ``max_iter`` is not enough.
    """
    if method not in METHODS:
        raise MethodError(f"unknown method {method!r}", column="method",
                          fix=f"use one of {', '.join(METHODS)}")
    from .model import predict_scaled
    Tg = np.linspace(*T_range, 21)
    wlo = max(W_range[0] / sc.W_scale, box[0] * 0.999)
    whi = min(W_range[1] / sc.W_scale, box[1] * 0.999)
    Wg = np.linspace(wlo, whi, 201)
    Wg = Wg[np.abs(Wg) > 1e-6]
    T, W = (a.ravel() for a in np.meshgrid(Tg, Wg * sc.W_scale))
    Tp = (T - sc.T_ref) / sc.T_scale
    p_np = FullParams(*(np.asarray(a, dtype=float) for a in p))
    U = sc.U_ref + sc.U_scale * predict_scaled(p_np, Tp, W / sc.W_scale, 0.0 * T)
    for k in range(max_iter + 1):
        w, _ = compensate_numpy(p, sc, box, U, T, 0.0 * T, method=method, iterations=k)
        if np.max(np.abs(w - W) / np.abs(W)) < rtol:
            return k
    raise MethodError(f"{method} needs more than {max_iter} iterations over the calibrated range",
                      column="iterations", fix="use method='halley' or a smaller rate range")


def build_compensator(p: FullParams | ProductParams, sc: Scaling, *, T_range, W_range,
                      method: str = "halley", iterations: int | None = None,
                      rtol: float = 1e-9, host: bool | None = None) -> Compensator:
    """A ready-to-call :class:`Compensator` (box and iteration count fixed here, once).

    ``rtol`` = 1e-9 (1e-7 %) is far below any gyro's noise and the done-when's 1e-4 %, and
    for paper 000's coefficients gives Halley 2 iterations, the paper's own count.
    ``host``: calls go to the CPU (True), to XLA on JAX's default device (False), or to
    the CPU where that device is the CPU or JAX was never started (None:
    :func:`fogbayes.support.lazy.jax_on_cpu`). On the CPU a one-off call below
    :data:`.compensate_loop.NUMPY_BELOW` samples runs the loop's source on whole arrays in
    NumPy, other calls the compiled loop (:class:`.compensate_loop.CompensationLoop`).
    Streams pass True: their chunks start and end in host memory, where a GPU only adds two
    transfers a chunk, and they always take the compiled loop.
    """
    if isinstance(p, ProductParams):
        p = product_to_full(p)
    if method not in METHODS:
        raise MethodError(f"unknown method {method!r}", column="method",
                          fix=f"use one of {', '.join(METHODS)}")
    box = monotone_box(p, T_range, sc)
    if iterations is None:
        iterations = 2 if method == "paper" else choose_iterations(
            p, sc, box, T_range, W_range, method=method, rtol=rtol)
    if int(iterations) != iterations or iterations < 0:
        raise MethodError(f"iterations must be a non-negative integer, got {iterations!r}",
                          column="iterations", fix="pass e.g. iterations=2")
    k = int(iterations)
    consts = FullParams(*(np.asarray(v, dtype=float) for v in p))
    sc_f = Scaling(*(float(v) for v in sc))
    recip = reciprocal_poly(consts, T_range, sc_f)
    kw = dict(method=method, iterations=k, recip=recip)
    fn = program(lambda U, T, t: _result(consts, sc_f, box, U, T, t, **kw))
    stream_fn = program(lambda U, T, t: _rate(consts, sc_f, box, U, T, t, **kw),
                        donate_argnums=0)
    loop = None
    if host or (host is None and jax_on_cpu()):  # one pass at memory speed
        from .compensate_loop import compile_loop

        loop = compile_loop(consts, sc_f, box, **kw)
    return Compensator(p, sc, box, k, method, fn, stream_fn, loop)


def _loop_result(loop, U, T, t) -> CompensationResult:
    """:class:`CompensationResult` of the compiled loop (arrays of one shape, any dtype)."""
    U, T, t = np.broadcast_arrays(*(np.asarray(a) for a in (U, T, t)))
    dt = np.result_type(U.dtype, np.float32)  # integer counts compute in float
    flat = [np.ascontiguousarray(a, dtype=dt).ravel() for a in (U, T, t)]
    rate = loop(np.empty(flat[0].size, dt), *flat).reshape(U.shape)
    return CompensationResult(rate, np.isfinite(rate))


def reciprocal_poly(p: FullParams, T_range, sc: Scaling, *, order: int = 6) -> np.ndarray:
    """Least-squares polynomial in T' for 1 / S_0(T) over the calibrated range widened by
    half on each side (the Newton/Halley start only: its error is corrected by the
    iterations; for paper 000's S_0, which varies by 3 %, the fit is good to 1e-10)."""
    M = np.asarray(p.M, dtype=float)
    a, b = ((np.asarray(T_range, float) - sc.T_ref) / sc.T_scale)
    half = (b - a) / 2
    x = np.linspace(a - half, b + half, 401)
    S0 = np.polynomial.polynomial.polyval(x, M[:, 0])
    if np.any(S0 == 0) or np.any(np.sign(S0) != np.sign(S0[0])):
        raise MethodError("the small-rate scale factor S_0(T) crosses zero in the range",
                          column="params", fix="check the fit: the gyro has no response there")
    return np.polynomial.polynomial.polyfit(x, 1.0 / S0, order)
