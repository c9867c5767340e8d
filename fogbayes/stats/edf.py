r"""Equivalent degrees of freedom (Greenhall & Riley 2004) and chi-square intervals.

:math:`\hat\sigma^2 \sim \sigma^2\chi^2_\nu/\nu`. Greenhall's general algorithm (PTTI 2003,
eqs. 7-10) for rate PSD :math:`\propto f^\alpha`, difference order ``d`` (2 Allan, 3 Hadamard),
factor ``m``, ``N`` phase points, filter ``F`` and stride ``S``:
:math:`1/\nu = [s_z(0)^2 + (1 - J/M)s_z(J/S)^2 + 2\sum_{j<J}(1 - j/M)s_z(j/S)^2] / (M s_z(0)^2)`,
evaluated exactly up to 2 000 terms, beyond by Gauss-Legendre quadrature between the kinks of
``s_z`` (relative error <= 1.6e-6). Unmodified, alpha <= 0, ``m(d+1) > 100``: ``F = infinity``.
Interval (NIST SP 1065 eq. 45): :math:`[\nu\hat\sigma^2/\chi^2_\nu((1+ci)/2),\ \nu\hat\sigma^2/\chi^2_\nu((1-ci)/2)]`.
"""

from __future__ import annotations

import numpy as np
from scipy import special

from ..support.tails import chi2_ppf

D_OF_KIND = {"oadev": 2, "adev": 2, "mdev": 2, "ohdev": 3, "hdev": 3}
_EXACT_TERMS = 2_000
_NEAR = 16  # integers taken one by one on each side of each kink of s_z
_GL_X, _GL_W = np.polynomial.legendre.leggauss(10)
_F_INF_LIMIT = 100  # Greenhall's J_max: above m (d+1) > 100 use F = infinity (alpha <= 0)


def _sw(t: np.ndarray, alpha: int) -> np.ndarray:
    a = abs(t)
    if alpha % 2 == 0:  # -|t|, |t|^3, |t|^5, |t|^7
        return -a if alpha == 2 else a ** (3 - alpha)
    with np.errstate(divide="ignore", invalid="ignore"):
        v = t ** (3 - alpha) * np.log(a)
    return np.where(a == 0, 0.0, v)


def _sx(t: np.ndarray, F: float, alpha: int) -> np.ndarray:
    if np.isinf(F):
        return _sw(t, alpha + 2)
    return F * F * (2 * _sw(t, alpha) - _sw(t - 1.0 / F, alpha) - _sw(t + 1.0 / F, alpha))


#: (-1)^k binom(2d, d + k), k = -d..d, per difference order d
_SZ_COEF = {d: np.array([(-1) ** k * special.comb(2 * d, d + k) for k in range(-d, d + 1)])
            for d in (1, 2, 3, 4)}


def _sz(t: np.ndarray, F: float, alpha: int, d: int) -> np.ndarray:
    """s_z at every t: one vectorised evaluation over the 2d + 1 shifts (module doc)."""
    t = np.asarray(t, dtype=float)
    shifted = t[None, :] + np.arange(-d, d + 1, dtype=float)[:, None]
    return _SZ_COEF[d] @ _sx(shifted, F, alpha)


def _filter_factor(alpha: int, d: int, m: int, modified: bool) -> float:
    if modified:
        return 1.0
    if alpha <= 0 and m * (d + 1) > _F_INF_LIMIT:
        return np.inf
    return float(m)


def _layout(d: int, m: int, n_phase: int, overlapping: bool, modified: bool):
    F = 1.0 if modified else float(m)
    S = float(m) if overlapping else 1.0
    L = m / F + m * d
    M = 1 + np.floor(S * (n_phase - L) / m)
    J = min(M, (d + 1) * S)
    return S, M, J


def _graded_nodes(lo: float, hi: float) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Legendre nodes and weights of the integral over [lo, hi], in pieces that double
    in width away from both ends (s_z is smooth inside a stretch but, for odd alpha, has
    t^k ln|t| kinks just beyond its ends)."""
    half = 0.5 * (hi - lo)
    steps = [0.0]
    w = 1.0
    while steps[-1] + w < half:
        steps.append(steps[-1] + w)
        w *= 2.0
    steps.append(half)
    left = lo + np.asarray(steps)
    edges = np.concatenate([left, (hi - (left - lo))[-2::-1]])
    a, b = edges[:-1, None], edges[1:, None]
    nodes = 0.5 * (a + b) + 0.5 * (b - a) * _GL_X
    return nodes.ravel(), (0.5 * (b - a) * _GL_W).ravel()


def _inner_points(n_inner: int, S: float) -> tuple[np.ndarray, np.ndarray]:
    """Points j (and weights) standing for the integers 1..n_inner of the basic sum.

    Up to :data:`_EXACT_TERMS` integers every one is taken. Beyond, s_z(j/S) is smooth
    between integer t = j/S but has kinks there (and, for alpha = 2, its whole mass: a
    spike of width 1/F at each integer), so the :data:`_NEAR` integers on each side of each
    kink (t = 0, 1, 2, ...) are taken one by one, and each stretch a..b between them stands
    for the integral over [a - 1/2, b + 1/2] plus Euler-Maclaurin's first end correction
    (-f'/24 at each end), the integral taken by graded Gauss-Legendre: a few hundred points
    instead of up to 3 S.
    """
    if n_inner <= _EXACT_TERMS:
        j = np.arange(1, n_inner + 1, dtype=float)
        return j, np.ones_like(j)
    kinks = S * np.arange(0, int(n_inner // S) + 1)
    near = np.concatenate([np.arange(max(1, int(np.ceil(c - _NEAR))),
                                     min(n_inner, int(np.floor(c + _NEAR))) + 1) for c in kinks])
    near = np.unique(near)
    bounds = np.concatenate([[0], near, [n_inner + 1]])
    pts, wts = [near.astype(float)], [np.ones(near.size)]
    for a, b in zip(bounds[:-1] + 1, bounds[1:] - 1):  # far stretches a..b
        if b < a:
            continue
        if b - a < 4 * _NEAR:  # short: every integer
            j = np.arange(a, b + 1, dtype=float)
            pts.append(j)
            wts.append(np.ones(j.size))
            continue
        x, w = _graded_nodes(a - 0.5, b + 0.5)
        # Euler-Maclaurin's first correction, -(f'(b + 1/2) - f'(a - 1/2)) / 24, with each
        # derivative a central difference over the neighbouring integers
        pts.append(np.concatenate([x, [b + 1.0, b, a, a - 1.0]]))
        wts.append(np.concatenate([w, np.array([-1.0, 1.0, 1.0, -1.0]) / 24.0]))
    return np.concatenate(pts), np.concatenate(wts)


def basic_sum(sz_of_t, J: float, M: float, S: float) -> float:
    """Greenhall eq. 10 for an ``s_z`` given as a function of t."""
    j, wt = _inner_points(int(J) - 1, S)
    z = sz_of_t(np.concatenate([[0.0, J / S], j / S]))  # one evaluation for every t
    total = z[0] ** 2 + (1 - J / M) * z[1] ** 2
    if j.size:
        total += 2 * float(np.sum(wt * (1 - j / M) * z[2:] ** 2))
    return float(total)


def edf_greenhall(alpha: int, d: int, m: int, n_phase: int, *, overlapping: bool = True,
                  modified: bool = False) -> float:
    """EDF of a d-th difference variance for pure power-law noise ``alpha``.

    Example:
        >>> round(edf_greenhall(0, 2, 1, 1001), 1)   # white rate, OADEV, m = 1 (allantools: 782.0)
        782.0
    """
    return edf_mixture({int(alpha): 1.0}, d, m, n_phase, overlapping=overlapping,
                       modified=modified)


def edf_mixture(weights: dict[int, float], d: int, m: int, n_phase: int, *,
                overlapping: bool = True, modified: bool = False) -> float:
    """EDF for a sum of independent power-law noises (``{alpha: variance share at this m}``).

    The filtered-noise autocovariances add, so :math:`s_z = \\sum_p w_p s_{z,p}/s_{z,p}(0)`
    goes into the same basic sum; a single noise gives :func:`edf_greenhall`.
    """
    S, M, J = _layout(d, m, n_phase, overlapping, modified)
    if M < 1:
        return float("nan")
    parts = [(w, alpha, _filter_factor(alpha, d, m, modified))
             for alpha, w in weights.items() if w > 0]
    norms = [float(_sz(np.zeros(1), F, a, d)[0]) for _, a, F in parts]

    def sz(t):
        return sum(w * _sz(t, F, a, d) / z0 for (w, a, F), z0 in zip(parts, norms))

    s0 = float(sz(np.zeros(1))[0])
    return M * s0 ** 2 / basic_sum(sz, J, M, S)


def edf_for_kind(alphas, ms, n: int, kind: str) -> np.ndarray:
    """Greenhall EDF per cluster size for rate data of length ``n`` (``n + 1`` phase points)."""
    d = D_OF_KIND[kind]
    overlapping = kind in ("oadev", "mdev", "ohdev")
    modified = kind == "mdev"
    return np.array([edf_greenhall(int(a), d, int(m), n + 1, overlapping=overlapping,
                                   modified=modified) for a, m in zip(alphas, ms)])


def chi2_interval(var: np.ndarray, edf: np.ndarray, ci: float = 0.9):
    """(low, high) bounds of the variance at confidence ``ci`` (two-sided, equal tails)."""
    var, edf = np.asarray(var, float), np.asarray(edf, float)
    lo = edf * var / chi2_ppf(0.5 + ci / 2, edf)
    hi = edf * var / chi2_ppf(0.5 - ci / 2, edf)
    return lo, hi
