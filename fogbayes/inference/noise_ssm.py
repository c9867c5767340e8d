"""O(n) Gaussian likelihood of a regression under white + flicker + Markov + random-walk noise.

y_t = x_t'beta + 1's_t + e_t, e_t ~ N(0, s2 w_t); s_{t+1,j} = phi_j s_{t,j} + u_{t,j}, u ~ N(0, s2 q_j):
a flicker bank (tau_j spaced by sqrt(10), shared variance v_f: a 1/f spectrum), free Gauss-Markov
components, and a random walk from 0. One Kalman pass whitens [y, X]: S = sum m v v' / F,
beta = S_XX^-1 S_Xy, RSS = sum m r^2 / F (from the whitened residual, for precision),
s2 = RSS / n_obs, log L = -1/2 [n_obs log(2 pi s2) + sum m log F + n_obs].
Hyperparameters: :mod:`fogbayes.inference.noise_fit` (the likelihood and gradient it maximises:
:mod:`fogbayes.inference.noise_kalman`, held to this module's definition by the tests).
"""

from __future__ import annotations

import math
from functools import partial
from typing import NamedTuple

import numpy as np

from ..support.lazy import lazy_module
from ..support.programs import program
from . import noise_kalman

# imported at first use: the fits run on the CPU filter (noise_kalman); JAX for its definitions
jax = lazy_module("jax")
jnp = lazy_module("jax.numpy")
Array = "jax.Array"  # annotations only

BANK_PER_DECADE = 2.0
BANK_SPAN = (0.5, 2.0)  # (x dt, x duration): the simulator's flicker reaches 1/T
UNROLL = 1  # compile time matters more than the last 25 % of scan speed
LOG_BOUNDS = {"flicker": (-25.0, 12.0), "rw": (-30.0, 8.0), "mvar": (-18.0, 12.0)}


class NoiseSpec(NamedTuple):
    """Static structure of the noise model (hashable: a jit static argument).

    dt: block step (s); bank_taus: flicker-bank time constants (s), () = no flicker;
    n_markov: number of free Gauss-Markov components; random_walk: include a random walk;
    tau_max: upper bound of a free Markov time constant (s); log_rw_max, log_mvar_max: upper
    bounds of the random walk's and of a free Markov component's log variance ratio (caps
    from a noise prior, :mod:`fogbayes.loop.noise_prior`; by default the top of
    :data:`LOG_BOUNDS`).
    """

    dt: float
    bank_taus: tuple[float, ...] = ()
    n_markov: int = 0
    random_walk: bool = True
    tau_max: float = 1e5
    log_rw_max: float = LOG_BOUNDS["rw"][1]
    log_mvar_max: float = LOG_BOUNDS["mvar"][1]

    @property
    def n_state(self) -> int:
        return len(self.bank_taus) + self.n_markov + int(self.random_walk)

    @property
    def n_theta(self) -> int:
        return int(bool(self.bank_taus)) + int(self.random_walk) + 2 * self.n_markov


def make_spec(dt: float, duration: float, *, n_markov: int = 0, random_walk: bool = True,
              flicker: bool = True, per_decade: float = BANK_PER_DECADE,
              span: tuple[float, float] = BANK_SPAN) -> NoiseSpec:
    """Flicker bank from span[0] dt to span[1] duration, ``per_decade`` components a decade."""
    taus: tuple[float, ...] = ()
    if flicker:
        lo, hi = span[0] * dt, max(span[1] * duration, 4.0 * span[0] * dt)
        k = int(math.floor(math.log10(hi / lo) * per_decade + 1e-9)) + 1
        taus = tuple(float(lo * 10 ** (j / per_decade)) for j in range(max(k, 1)))
    return NoiseSpec(float(dt), taus, int(n_markov), bool(random_walk), float(10 * duration))


class NoiseParams(NamedTuple):
    """Hyperparameters, variances relative to the white variance s2 (log scale)."""

    log_flicker: Array
    log_rw: Array
    markov_logvar: Array  # (M,)
    markov_logtau: Array  # (M,) log seconds


def unpack(spec: NoiseSpec, theta) -> NoiseParams:
    """Unconstrained vector -> :class:`NoiseParams` (absent parts get -inf-like values)."""
    if not hasattr(theta, "shape"):  # NumPy and JAX arrays (traced ones too) index alike
        theta = np.asarray(theta, dtype=float)
    i = 0
    lf = -60.0
    if spec.bank_taus:
        lf, i = theta[i], i + 1
    lrw = -60.0
    if spec.random_walk:
        lrw, i = theta[i], i + 1
    m = spec.n_markov
    return NoiseParams(lf, lrw, theta[i:i + m], theta[i + m:i + 2 * m])


def pack(spec: NoiseSpec, p: NoiseParams) -> np.ndarray:
    parts = []
    if spec.bank_taus:
        parts.append([float(p.log_flicker)])
    if spec.random_walk:
        parts.append([float(p.log_rw)])
    parts += [np.asarray(p.markov_logvar, float), np.asarray(p.markov_logtau, float)]
    return np.concatenate([np.ravel(a) for a in parts]) if parts else np.zeros(0)


def bounds(spec: NoiseSpec) -> list[tuple[float, float]]:
    b = []
    if spec.bank_taus:
        b.append(LOG_BOUNDS["flicker"])
    if spec.random_walk:
        b.append((LOG_BOUNDS["rw"][0], spec.log_rw_max))
    b += [(LOG_BOUNDS["mvar"][0], spec.log_mvar_max)] * spec.n_markov
    b += [(math.log(spec.dt / 2.0), math.log(spec.tau_max))] * spec.n_markov
    return b


def system(spec: NoiseSpec, p: NoiseParams) -> tuple[Array, Array, Array]:
    """Diagonal transition phi (d,), process variance q (d,), initial variance p0 (d,)."""
    phis, qs, p0s = [], [], []
    if spec.bank_taus:
        tb = jnp.asarray(spec.bank_taus)
        ph = jnp.exp(-spec.dt / tb)
        v = jnp.exp(p.log_flicker)
        phis.append(ph)
        qs.append(v * -jnp.expm1(-2.0 * spec.dt / tb))
        p0s.append(v * jnp.ones_like(tb))
    if spec.n_markov:
        ph = jnp.exp(-spec.dt / jnp.exp(p.markov_logtau))
        v = jnp.exp(p.markov_logvar)
        phis.append(ph)
        qs.append(v * -jnp.expm1(-2.0 * spec.dt / jnp.exp(p.markov_logtau)))
        p0s.append(v)
    if spec.random_walk:
        phis.append(jnp.ones(1))
        qs.append(jnp.exp(p.log_rw)[None])
        p0s.append(jnp.zeros(1))  # the walk's starting level is the intercept
    if not phis:  # white noise only: no state
        return jnp.zeros(0), jnp.zeros(0), jnp.zeros(0)
    return jnp.concatenate(phis), jnp.concatenate(qs), jnp.concatenate(p0s)


def _filter(phi, q, p0, Y, mask, w):
    """Innovations V (n, C) and relative variances F (n,) of every column of Y: the package's
    Kalman filter (:func:`fogbayes.models.statespace.linear_gaussian_filter`) on the diagonal
    system, observed through the sum of the states."""
    from ..models.statespace import linear_gaussian_filter  # JAX: imported at first use

    return linear_gaussian_filter(lambda M: phi[:, None] * M, jnp.diag(q), jnp.ones_like(phi),
                                  jnp.diag(p0), Y, w, mask, states=False, unroll=UNROLL)


class GLSResult(NamedTuple):
    """Profile-likelihood GLS fit at fixed noise hyperparameters.

    loglik: maximised over beta and s2; beta (p,), cov_beta (p, p) = s2 S_XX^-1;
    sigma2: s2; innov (n, 1+p) innovations of [y, X]; F (n,) their relative variances.
    """

    loglik: Array
    beta: Array
    cov_beta: Array
    sigma2: Array
    innov: Array
    F: Array


def _profile(V, F, mask, pad):
    """GLS normal equations and profile log-likelihood from innovations of [y, X]."""
    wv = V * (mask / F)[:, None]
    S = wv.T @ V
    Sxx = S[1:, 1:] + jnp.diag(pad)
    Sxy = S[1:, 0]
    L = jnp.linalg.cholesky(Sxx)
    beta = jax.scipy.linalg.cho_solve((L, True), Sxy)
    r = V[:, 0] - V[:, 1:] @ beta  # module doc, "Precision"
    rss = jnp.sum((mask / F) * r * r)
    nobs = mask.sum()
    s2 = rss / nobs
    ll = -0.5 * (nobs * jnp.log(2 * jnp.pi * s2) + jnp.sum(mask * jnp.log(F)) + nobs)
    cov = s2 * jax.scipy.linalg.cho_solve((L, True), jnp.eye(Sxx.shape[0]))
    return ll, beta, cov, s2


def gls(spec: NoiseSpec, theta, y, X, mask, w) -> GLSResult:
    """GLS fit of y (n,) on X (n, p) under the noise model ``theta`` (see module doc).

    ``mask`` (n,) 1 for observed blocks, 0 for missing ones; ``w`` (n,) white-variance
    weights. One filter pass over [y, X] (shared compiled shape, see :func:`filter_padded`).
    """
    mask = np.asarray(mask, float)
    Y = np.column_stack([np.where(mask > 0, y, 0.0), X])
    V, F = filter_padded(spec, theta, Y, mask, w)
    ll, beta, cov, s2 = profile_np(V, F, mask)
    return GLSResult(ll, beta, cov, s2, V, F)


def profile_np(V: np.ndarray, F: np.ndarray, mask: np.ndarray):
    """(loglik, beta, cov_beta, s2) from innovations V of [y, X] (NumPy, float64)."""
    g = mask / F
    S = (V * g[:, None]).T @ V
    Sxx, Sxy = S[1:, 1:], S[1:, 0]
    try:
        L = np.linalg.cholesky(Sxx)
        beta = np.linalg.solve(L.T, np.linalg.solve(L, Sxy))
        Li = np.linalg.inv(L)
        inv = Li.T @ Li
    except np.linalg.LinAlgError:  # collinear columns: minimum-norm solution
        inv = np.linalg.pinv(Sxx, hermitian=True)
        beta = inv @ Sxy
    nobs = float(mask.sum())
    r = V[:, 0] - V[:, 1:] @ beta  # module doc, "Precision"
    s2 = max(float(np.sum(g * r * r)), 1e-300) / nobs
    ll = -0.5 * (nobs * np.log(2 * np.pi * s2) + float(np.sum(mask * np.log(F))) + nobs)
    return float(ll), beta, s2 * inv, s2


def _negll(spec, theta, y, X, mask, w, pad):
    phi, q, p0 = system(spec, unpack(spec, theta))
    Y = jnp.concatenate([y[:, None], X], axis=1) * mask[:, None]
    V, F = _filter(phi, q, p0, Y, mask, w)
    return -_profile(V, F, mask, pad)[0]


@partial(program, static_argnums=0)
def _negll_and_grad(spec, theta, y, X, mask, w, pad):
    """-log L and its gradient by JAX autodiff: the definition that
    :func:`fogbayes.inference.noise_kalman.negloglik` (what the fits call) is tested against."""
    return jax.value_and_grad(lambda th: _negll(spec, th, y, X, mask, w, pad))(theta)


def padded_width(p: int, multiple: int = 8) -> int:
    """Columns after padding ``p`` to a multiple of ``multiple`` (one compiled shape per size)."""
    return max(multiple, int(math.ceil(p / multiple)) * multiple)


def pad_columns(X: np.ndarray, multiple: int = 8, *,
                width: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Pad X with zero columns to ``width`` (default :func:`padded_width`), and the ridge
    ``pad`` that keeps their normal equations regular: a padded column gets beta 0 and
    leaves the likelihood unchanged."""
    X = np.asarray(X, dtype=float)
    p = X.shape[1]
    P = padded_width(p, multiple) if width is None else int(width)
    Xp = np.zeros((X.shape[0], P))
    Xp[:, :p] = X
    pad = np.zeros(P)
    pad[p:] = 1.0
    return Xp, pad


@partial(program, static_argnums=0)
def whiten_raw(spec: NoiseSpec, theta, Y, mask, w):
    """Raw innovations (n, C) and relative variances F (n,) of the columns of Y."""
    phi, q, p0 = system(spec, unpack(spec, theta))
    return _filter(phi, q, p0, Y * mask[:, None], mask, w)


#: the widest chunk of columns :func:`filter_padded` masks and filters at once
MAX_FILTER_COLUMNS = 256


def _side_by_side(blocks: list[np.ndarray], j: int, k: int) -> np.ndarray:
    """Columns ``j:k`` of the blocks placed side by side."""
    parts, at = [], 0
    for b in blocks:
        lo, hi = max(j - at, 0), min(k - at, b.shape[1])
        if lo < hi:
            parts.append(b[:, lo:hi])
        at += b.shape[1]
    if not parts:
        return np.zeros((blocks[0].shape[0], 0))
    return parts[0] if len(parts) == 1 else np.column_stack(parts)


def filter_padded(spec: NoiseSpec, theta, Y, mask, w):
    """:func:`whiten_raw`'s values by the CPU filter of :mod:`.noise_kalman` (any width, no
    compilation per shape), :data:`MAX_FILTER_COLUMNS` columns at a time into one output.

    The columns share the gains and are filtered independently, so chunks change no value;
    they bound the memory to the output plus one masked chunk (a screening whitens
    thousands of candidate columns). ``Y``: an (n, C) array, or a list of (n, k) arrays
    side by side (then never stacked whole). Returns NumPy (V (n, C), F (n,)).
    """
    blocks = [np.asarray(b, float) for b in Y] if isinstance(Y, list) else [np.asarray(Y, float)]
    c = sum(b.shape[1] for b in blocks)
    keep = (np.asarray(mask, float) > 0)[:, None]
    out = np.empty((blocks[0].shape[0], c))
    F = None
    for j in range(0, max(c, 1), MAX_FILTER_COLUMNS):
        part = np.where(keep, _side_by_side(blocks, j, j + MAX_FILTER_COLUMNS), 0.0)
        V, F = noise_kalman.innovations(spec, theta, part, mask, w, grad=False)[:2]
        out[:, j:j + part.shape[1]] = V
    return out, F


def whiten(spec: NoiseSpec, theta, Y, mask, w):
    """Whitened columns L^-1 Y (n, C): innovations / sqrt(F), 0 at missing blocks (``Y`` as
    in :func:`filter_padded`)."""
    V, F = filter_padded(spec, theta, Y, mask, w)
    scale = (np.asarray(mask) / np.sqrt(F))[:, None]
    if V.flags.writeable:  # a chunked filter's own output: scaled in place
        V *= scale
        return V, F
    return V * scale, F


def whiten_transpose(spec: NoiseSpec, theta, Z, mask, w) -> np.ndarray:
    """L^-T Z (n, C): the transpose of :func:`whiten`'s linear map (the filter's gains do not
    depend on the data), so L^-T (L^-1 X) = S^-1 X, what a GLS estimate's sandwich needs
    (the reverse recursion of :func:`fogbayes.inference.noise_kalman.whiten_transpose`)."""
    return noise_kalman.whiten_transpose(spec, theta, Z, mask, w)


def pointwise_loglik(spec: NoiseSpec, theta, y, X, mask, w, betas, sigma2) -> np.ndarray:
    """One-step-ahead predictive log densities log p(y_t | y_<t, beta_s) for draws betas (S, p).

    Returns (S, n_obs): the pointwise log-likelihood ArviZ needs for WAIC / PSIS-LOO.
    """
    mask = np.asarray(mask, float)
    Y = np.column_stack([np.where(mask > 0, y, 0.0), X])
    V, F = filter_padded(spec, theta, Y, mask, w)
    obs = mask > 0
    r = V[obs, :1].T - np.asarray(betas) @ V[obs, 1:].T  # (S, n_obs) innovations
    f = sigma2 * F[obs]
    return -0.5 * (np.log(2 * np.pi * f)[None, :] + r * r / f[None, :])
