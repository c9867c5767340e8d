"""Least squares: closed form (QR) for linear models, optax L-BFGS for the general case.

min_b sum_i w_i (y_i - X_i b)^2 with sqrt(w) X = QR: b = R^-1 Q' sqrt(w) y,
s^2 = sum w r^2 / (n - p), Cov = s^2 R^-1 R^-T (independent errors; coloured noise:
:func:`fogbayes.inference.bayes.fit_linear_bayes`). :func:`minimize` (L-BFGS in one
``lax.while_loop``), :func:`fit_nonlinear` (Gauss-Newton covariance s^2 (J'J)^-1),
:func:`lstsq_optax`; all jit- and vmap-able.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, NamedTuple

import numpy as np

from ..support.lazy import lazy_module

# JAX and optax load on first use: the NumPy path of a one-off fit (``fogbayes fit``) never
# needs them (0.4 s of a CLI call).
jax = lazy_module("jax")
jnp = lazy_module("jax.numpy")
optax = lazy_module("optax")
Array = Any


def ravel_pytree(tree):
    from jax.flatten_util import ravel_pytree as ravel

    return ravel(tree)


def solve_triangular(a, b, **kw):
    from jax.scipy.linalg import solve_triangular as solve

    return solve(a, b, **kw)


class FitResult(NamedTuple):
    """Result of a least-squares fit.

    Attributes:
        params: estimated parameters (p,) (a pytree for :func:`fit_nonlinear`).
        covariance: (p, p) parameter covariance (flattened-parameter order).
        stderr: (p,) standard errors, sqrt(diag(covariance)).
        residual: (n,) y - fitted.
        converged: False for a rank-deficient design or an optimiser that hit max_iter.
        n_iter: optimiser iterations (0 for the closed form).
        loss: 0.5 * weighted residual sum of squares.
        sigma2: residual variance s^2 = wRSS / (n - p).
        dof: n - p.
    """

    params: Any
    covariance: Array
    stderr: Array
    residual: Array
    converged: Array
    n_iter: Array
    loss: Array
    sigma2: Array
    dof: Array


def _row_weights(y: Array, weights: Array | None) -> Array:
    return jnp.ones_like(y) if weights is None else jnp.asarray(weights, y.dtype)


def lstsq(X: Array, y: Array, weights: Array | None = None, *, rcond: float = 1e-10) -> FitResult:
    """Closed-form weighted least squares by QR (see module docstring).

    Args:
        X: (n, p) design matrix (use a centred, scaled basis).
        y: (n,) observations.
        weights: (n,) non-negative weights (e.g. samples per block average), or None.
        rcond: the design counts as rank deficient when ``min |R_ii| < rcond * max |R_ii|``;
            it then gets the minimum-norm solution and ``converged=False``.

    Example:
        >>> import jax.numpy as jnp
        >>> X = jnp.stack([jnp.ones(4), jnp.arange(4.0)], 1)
        >>> fit = lstsq(X, 1.0 + 2.0 * jnp.arange(4.0))
        >>> [round(float(v), 9) for v in fit.params]
        [1.0, 2.0]
    """
    if all(isinstance(a, np.ndarray) for a in (X, y)) and (
            weights is None or isinstance(weights, np.ndarray)):
        # concrete NumPy inputs (a workflow's one-off fit): the same QR by LAPACK, without
        # JAX compiling each primitive again for every new record length
        return _lstsq_numpy(np.asarray(X, float), np.asarray(y, float),
                            None if weights is None else np.asarray(weights, float), rcond)
    X, y = jnp.asarray(X, float), jnp.asarray(y, float)
    w = _row_weights(y, weights)
    sw = jnp.sqrt(w)
    Q, R = jnp.linalg.qr(X * sw[:, None])
    n, p = X.shape
    d = jnp.abs(jnp.diag(R))
    full_rank = jnp.min(d) > rcond * jnp.max(d)
    eye = jnp.eye(p, dtype=X.dtype)
    # full rank: triangular solves; otherwise the minimum-norm (pseudo-inverse) solution,
    # finite but not identified -- reported through ``converged=False``
    Rinv = jax.lax.cond(full_rank, lambda R: solve_triangular(R, eye, lower=False),
                        lambda R: jnp.linalg.pinv(R, rtol=rcond), R)
    return _finish(X, y, w, sw, Q, Rinv, full_rank, jnp)


def _lstsq_numpy(X, y, w, rcond: float) -> FitResult:
    """:func:`lstsq` in NumPy/LAPACK for concrete inputs (identical formulas; R^-1 by NumPy's
    solve: R is p x p, and importing scipy.linalg would cost ~0.13 s of a ``fogbayes fit``)."""
    w = np.ones_like(y) if w is None else w
    sw = np.sqrt(w)
    Q, R = np.linalg.qr(X * sw[:, None])
    d = np.abs(np.diag(R))
    full_rank = bool(np.min(d) > rcond * np.max(d))
    p = X.shape[1]
    Rinv = np.linalg.solve(R, np.eye(p)) if full_rank else np.linalg.pinv(R, rcond=rcond)
    return _finish(X, y, w, sw, Q, Rinv, full_rank, np)


def _finish(X, y, w, sw, Q, Rinv, full_rank, xp) -> FitResult:
    """Estimate, residual variance and covariance from the QR pieces (``xp``: np or jnp)."""
    n, p = X.shape
    beta = Rinv @ (Q.T @ (y * sw))
    resid = y - X @ beta
    dof = xp.asarray(n - p, float)
    wrss = xp.sum(w * resid**2)
    s2 = wrss / xp.maximum(dof, 1.0)
    cov = s2 * Rinv @ Rinv.T
    ok = full_rank & (dof > 0) & xp.all(xp.isfinite(beta))
    return FitResult(beta, cov, xp.sqrt(xp.diag(cov)), resid, ok, xp.asarray(0),
                     0.5 * wrss, s2, dof)


# -- identifiability: is the design well enough conditioned for the coefficients to mean
#    something? ---------------------------------------------------------------------------
#: Condition number of the centred, scaled (row-weighted) design above which the fit is
#: reported as not identifiable. A centred, scaled polynomial design has cond ~ 1e1 ... 1e3
#: (paper-style thermal and bias-t fits: 2 ... 60); at 1e6 a combination of the terms with
#: norm 1 changes the fitted values by only 1e-6 of what the best-determined one does, so
#: the data cannot tell those terms apart and their coefficients are set by the noise
#: (standard errors inflated ~1e6 times) and by rounding.
CONDITION_LIMIT = 1e6
#: A covariate whose range in the fit data is below this fraction of max(1, |value|) (deg C,
#: deg C/min) does not vary: its scaled column is rounding noise or zero. 1e-8 deg C is four
#: orders below any thermometer's resolution.
CONSTANT_RTOL = 1e-8


class Conditioning(NamedTuple):
    """Singular values (descending) and right singular vectors (rows of ``vectors``, same
    order) of the row-weighted design ``sqrt(w) X``; ``condition_number`` = s_max / s_min
    (inf when rank deficient)."""

    condition_number: float
    singular_values: np.ndarray
    vectors: np.ndarray


def conditioning(X, weights=None) -> Conditioning:
    """:class:`Conditioning` of ``sqrt(w) X`` (NumPy; the SVD of the p x p R of a QR)."""
    X = np.asarray(X, dtype=float)
    w = np.ones(X.shape[0]) if weights is None else np.asarray(weights, dtype=float)
    if not (np.all(np.isfinite(X)) and np.all(np.isfinite(w))):
        from ..errors import NonFiniteError

        raise NonFiniteError("the design matrix or its weights hold NaN or infinity",
                             column="design", fix="check the covariates of the fit")
    R = np.linalg.qr(X * np.sqrt(w)[:, None], mode="r")
    _, s, vt = np.linalg.svd(R)
    return Conditioning(float(s[0] / s[-1]) if s[-1] > 0 else float("inf"), s, vt)


def conditioning_from_covariance(cov, sigma2) -> Conditioning:
    """:class:`Conditioning` from ``Cov = s^2 (X^T W X)^-1`` (a fleet fit keeps no design).

    The eigenvalues of ``Cov / s^2`` are ``1 / s_i^2``; with the pseudo-inverse of a rank
    deficient design, the null directions have eigenvalue 0 (singular value 0). Agrees with
    :func:`conditioning` to ~1e-12 relative for a well-conditioned design.
    """
    return conditionings_from_covariances(np.asarray(cov, dtype=float)[None],
                                          np.asarray([sigma2], dtype=float))[0]


def conditionings_from_covariances(cov, sigma2) -> list[Conditioning]:
    """:func:`conditioning_from_covariance` of each of ``S`` fits (``cov`` (S, p, p),
    ``sigma2`` (S,)) in one stacked eigendecomposition (a fleet: one NumPy call, not S)."""
    cov = np.asarray(cov, dtype=float)
    s2 = np.asarray(sigma2, dtype=float).reshape(-1)
    n, p = cov.shape[0], cov.shape[-1]
    good = np.isfinite(s2) & (s2 > 0) & np.all(np.isfinite(cov), axis=(1, 2))
    out = [Conditioning(float("inf"), np.full(p, np.nan), np.eye(p)) for _ in range(n)]
    if not good.any():
        return out
    c = cov[good]
    lam, vec = np.linalg.eigh((c + c.transpose(0, 2, 1)) / (2.0 * s2[good, None, None]))
    for i, lam_i, vec_i in zip(np.flatnonzero(good), lam, vec):  # ascending: largest s first
        null = lam_i <= 1e-14 * lam_i[-1]
        s = np.where(null, 0.0, 1.0 / np.sqrt(np.where(null, 1.0, lam_i)))
        order = np.argsort(-s, kind="stable")
        s, vt = s[order], vec_i.T[order]
        out[i] = Conditioning(float(s[0] / s[-1]) if s[-1] > 0 else float("inf"), s, vt)
    return out


def identifiability(basis, lo, hi, cond: Conditioning, *,
                    condition_limit: float = CONDITION_LIMIT) -> dict:
    """Whether the coefficients of a polynomial ``basis`` are identified by the fit data.

    Not identified when a covariate does not vary over the data (``lo``/``hi``: its range;
    its terms are then collinear with the intercept: e.g. dT/dt on a single linear ramp),
    or when the condition number of the centred, scaled design exceeds ``condition_limit``;
    the near-null right singular vectors say which terms are collinear and how.
    Returns a JSON-able dict: ``identifiable``, ``condition_number``, ``condition_limit``,
    ``constant_covariates``, ``collinear_terms``, ``relation``, ``reason``.
    """
    labels = basis.labels()
    names = list(basis.names)
    kappa = float(cond.condition_number)
    collinear: list[str] = []
    reasons: list[str] = []

    def add(terms):
        collinear.extend(t for t in terms if t not in collinear)

    constant = []
    for c, (a, b) in enumerate(zip(np.asarray(lo, float), np.asarray(hi, float))):
        if b - a <= CONSTANT_RTOL * max(1.0, abs(a), abs(b)):
            constant.append(names[c])
            terms = [labels[k] for k, e in enumerate(basis.terms) if e[c] > 0]
            add(["1", *terms] if (0,) * len(names) in basis.terms else terms)
            reasons.append(f"covariate '{names[c]}' does not vary in the fit data "
                           f"({a:.9g} ... {b:.9g}, spread {b - a:.2g}), so its terms {', '.join(terms)} are "
                           "collinear with the intercept '1'")
    relation = ""
    if not kappa <= condition_limit:  # also inf / nan
        s = np.asarray(cond.singular_values, float)
        weak = [i for i in range(s.size) if not s[i] * condition_limit >= s[0]] or [s.size - 1]
        tied: list[str] = []
        for i in weak:
            v = np.asarray(cond.vectors[i], float)
            v = v * np.sign(v[np.argmax(np.abs(v))])  # sign: largest component positive
            big = [k for k in np.argsort(-np.abs(v), kind="stable") if abs(v[k]) >= 0.1]
            tied.extend(labels[k] for k in big if labels[k] not in tied)
            if not relation:
                relation = " ".join(f"{v[k]:+.3g}*[{labels[k]}]" for k in big) + " ~ 0"
        add(tied)
        reasons.append(f"the centred, scaled design has condition number {kappa:.3g} > "
                       f"{condition_limit:g}: {relation} (near-null singular vector), so the "
                       f"terms {', '.join(tied)} cannot be told apart")
    return {"identifiable": not reasons, "condition_number": kappa,
            "condition_limit": float(condition_limit), "constant_covariates": constant,
            "collinear_terms": collinear, "relation": relation, "reason": "; ".join(reasons)}


def lstsq_gram(X: Array, y: Array, weights: Array | None = None, *,
               rcond: float = 1e-10) -> FitResult:
    """Weighted least squares by the normal equations (Cholesky of ``G = X^T W X``).

    ``b_hat = G^{-1} X^T W y``, ``Cov = s^2 G^{-1}``. Squaring the condition number is
    harmless in a centred, scaled basis (cond(X) ~ 1e1 ... 1e2, so cond(G) <= 1e4 and
    float64 keeps ~12 digits), and the work is one pass over X plus a p x p solve, which
    batches well: this is the path for ``jax.vmap`` over many sensors on CPU, where a
    batched QR is slower than a loop (benchmarks/RESULTS_thermal.md). Same result as
    :func:`lstsq` (tested to 1e-10 relative).
    """
    X, y = jnp.asarray(X, float), jnp.asarray(y, float)
    w = _row_weights(y, weights)
    n, p = X.shape
    Xw = X * w[:, None]
    G = Xw.T @ X
    L = jnp.linalg.cholesky(G)
    eye = jnp.eye(p, dtype=X.dtype)
    Linv = solve_triangular(L, eye, lower=True)
    Ginv = Linv.T @ Linv
    beta = Ginv @ (Xw.T @ y)
    resid = y - X @ beta
    dof = jnp.asarray(n - p, float)
    wrss = jnp.sum(w * resid**2)
    s2 = wrss / jnp.maximum(dof, 1.0)
    cov = s2 * Ginv
    d = jnp.abs(jnp.diag(L))  # diag(L) ~ diag(R): same rank test as the QR path
    ok = (jnp.min(d) > rcond * jnp.max(d)) & (dof > 0) & jnp.all(jnp.isfinite(beta))
    return FitResult(beta, cov, jnp.sqrt(jnp.abs(jnp.diag(cov))), resid, ok, jnp.asarray(0),
                     0.5 * wrss, s2, dof)


class MinimizeResult(NamedTuple):
    params: Any
    loss: Array
    grad_norm: Array
    n_iter: Array
    converged: Array


def _lbfgs_step(loss_fn: Callable[[Any], Array], opt):
    """One optax L-BFGS iteration (zoom line search): (params, state) -> (params, state, loss).

    The one driver of optax L-BFGS in fogbayes; :func:`minimize` loops it to a gradient
    tolerance and :func:`lbfgs_scan` a fixed number of times."""
    value_and_grad = optax.value_and_grad_from_state(loss_fn)

    def step(params, state):
        value, grad = value_and_grad(params, state=state)
        updates, state = opt.update(grad, state, params, value=value, grad=grad,
                                    value_fn=loss_fn)
        return optax.apply_updates(params, updates), state, value

    return step


def minimize(loss_fn: Callable[[Any], Array], init: Any, *, max_iter: int = 500,
             tol: float = 1e-9, memory_size: int = 20,
             grad_norm: Callable[[Any], Array] | None = None) -> MinimizeResult:
    """Minimise ``loss_fn`` from ``init`` with optax L-BFGS (zoom line search) in one while_loop.

    Stops when ``grad_norm`` of the gradient (Euclidean when None) falls below ``tol``
    (``converged=True``), when it is not finite, or after ``max_iter`` iterations
    (``converged=False``). Scale the problem so that the loss and its gradient are of order
    one; ``tol`` is absolute. Under ``vmap`` each problem keeps its own stopping point.
    """
    opt = optax.lbfgs(memory_size=memory_size)
    step = _lbfgs_step(loss_fn, opt)
    grad_norm = optax.tree.norm if grad_norm is None else grad_norm  # optax loads lazily

    def going(carry):
        _, state = carry
        k = optax.tree.get(state, "count")
        # the zoom line search stores the gradient at the accepted point in the state
        g = grad_norm(optax.tree.get(state, "grad"))
        return (k == 0) | ((k < max_iter) & (g >= tol) & jnp.isfinite(g))

    params, state = jax.lax.while_loop(going, lambda c: step(*c)[:2], (init, opt.init(init)))
    # the line search left the value and gradient at the accepted point in the state (the
    # loop runs at least once): no further copy of the gradient program to compile
    value, gnorm = optax.tree.get(state, "value"), grad_norm(optax.tree.get(state, "grad"))
    return MinimizeResult(params, value, gnorm, optax.tree.get(state, "count"),
                          (gnorm < 10 * tol) & jnp.isfinite(value))


def lbfgs_scan(loss_fn: Callable[[Any], Array], init: Any, *, steps: int):
    """A fixed number of optax L-BFGS steps in one ``lax.scan``: (params, loss trace).

    For callers that vmap over many problems or want the whole loss trace (to judge
    convergence from its tail); :func:`minimize` stops on a gradient tolerance instead.
    """
    opt = optax.lbfgs()
    step = _lbfgs_step(loss_fn, opt)

    def scan_step(carry, _):
        params, state, value = step(*carry)
        return (params, state), value

    (params, _), trace = jax.lax.scan(scan_step, (init, opt.init(init)), None, length=steps)
    return params, trace


def fit_nonlinear(residual_fn: Callable[[Any], Array], init: Any, *, max_iter: int = 500,
                  tol: float = 1e-9) -> FitResult:
    """Nonlinear least squares ``min 0.5 sum r(theta)^2`` by L-BFGS, Gauss-Newton covariance.

    ``residual_fn(params) -> (n,)`` should already include any weights (``sqrt(w) r``)
    and be scaled to order one. ``Cov = s^2 (J^T J)^{-1}``, ``J = d r / d theta`` at the
    optimum, ``s^2 = sum r^2 / (n - p)``.
    """
    flat0, unravel = ravel_pytree(init)

    def loss(flat):
        r = residual_fn(unravel(flat))
        return 0.5 * jnp.sum(r * r)

    res = minimize(loss, flat0, max_iter=max_iter, tol=tol)
    r = residual_fn(unravel(res.params))
    J = jax.jacfwd(lambda f: residual_fn(unravel(f)))(res.params)
    n, p = J.shape
    dof = jnp.asarray(n - p, float)
    s2 = jnp.sum(r * r) / jnp.maximum(dof, 1.0)
    cov = s2 * jnp.linalg.pinv(J.T @ J)
    return FitResult(unravel(res.params), cov, jnp.sqrt(jnp.diag(cov)), r, res.converged,
                     res.n_iter, res.loss, s2, dof)


def lstsq_optax(X: Array, y: Array, weights: Array | None = None, *, max_iter: int = 500,
                tol: float = 1e-10) -> FitResult:
    """The linear least-squares problem of :func:`lstsq`, solved by the optax path.

    ``y`` is standardised first (so that the loss and ``tol`` are of order one) and the
    result mapped back; the covariance is the Gauss-Newton one, which for a linear model
    equals the closed form's ``s^2 (X^T W X)^{-1}``.
    """
    X, y = jnp.asarray(X, float), jnp.asarray(y, float)
    w = _row_weights(y, weights)
    sw = jnp.sqrt(w)
    scale = jnp.maximum(jnp.std(y), jnp.finfo(y.dtype).tiny)
    res = fit_nonlinear(lambda b: sw * (y / scale - X @ b), jnp.zeros(X.shape[1], float),
                        max_iter=max_iter, tol=tol)
    beta = res.params * scale
    resid = y - X @ beta
    return res._replace(params=beta, residual=resid, covariance=res.covariance * scale**2,
                        stderr=res.stderr * scale, loss=res.loss * scale**2,
                        sigma2=res.sigma2 * scale**2)
