r"""Joint covariance of overlapping Allan-variance estimates at several cluster sizes.

With :math:`d_i = S_{i+2m} - 2S_{i+m} + S_i` (phase in samples) and a generalized
autocovariance :math:`\Gamma` of ``S``, :math:`G(x) = \sum_{a,b} c_a c_b \Gamma(x + b m_2 - a m_1)`,
``c = (1, -2, 1)``, and for Gaussian noise
:math:`\mathrm{Cov}(\hat\sigma^2_1, \hat\sigma^2_2) = 2 \sum_x n(x) G(x)^2 / ((2 m_1^2 M_1)(2 m_2^2 M_2))`.
:math:`\Gamma` at unit scale: quantization :math:`\delta_k`, white rate :math:`-|k|/2`, flicker
:math:`k^2\ln|k|`, rate random walk :math:`(|k|^3-|k|)/12`. The covariance is a quadratic form in
the noise scales (tensor ``T``, built in NumPy, evaluated in JAX); a rate ramp ``r`` adds
:math:`c = r m^2` to each :math:`d_i` and a term linear in the scales (tensor ``U``).
"""

from __future__ import annotations

import functools
from typing import NamedTuple

import numpy as np

from ..support.xp import namespace

NOISE_TYPES = ("quantization", "white", "flicker", "rrw")
_C = np.array([1.0, -2.0, 1.0])
_MAX_LAGS = 2000  # lags evaluated per pair; beyond, a strided Riemann sum (smooth G)
_FLICKER_TAIL = 8  # flicker G decays like x^-2: sum lags up to 8 m beyond the support


class CovTensors(NamedTuple):
    """Moments of the overlapping AVAR per unit noise scale, for a fixed tau grid."""

    ms: np.ndarray      # (K,) cluster sizes
    counts: np.ndarray  # (K,) number of terms M
    expect: np.ndarray  # (P, K) expected AVAR of each noise type at unit scale
    T: np.ndarray       # (K, K, P, P) covariance tensor: Cov = sum_pq s_p s_q T[..., p, q]
    U: np.ndarray       # (K, K, P) ramp cross term: Cov += ramp^2 sum_p s_p U[..., p]


def gamma_phase(k: np.ndarray, noise: str) -> np.ndarray:
    """Generalized autocovariance of the phase ``S`` at lag ``k`` (unit scale)."""
    a = np.abs(k)
    if noise == "quantization":
        return (a == 0).astype(float)
    if noise == "white":
        return -a / 2.0
    if noise == "flicker":
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(a == 0, 0.0, a * a * np.log(np.where(a == 0, 1.0, a)))
    if noise == "rrw":
        return (a ** 3 - a) / 12.0
    raise ValueError(f"unknown noise type {noise!r}")


def expected_avar(m: np.ndarray, noise: str) -> np.ndarray:
    """Expected overlapping AVAR at unit scale: ``(6 G(0) - 8 G(m) + 2 G(2m)) / (2 m^2)``."""
    m = np.asarray(m, float)
    var_d = (6 * gamma_phase(np.zeros_like(m), noise) - 8 * gamma_phase(m, noise)
             + 2 * gamma_phase(2 * m, noise))
    return var_d / (2 * m * m)


def _cross(x: np.ndarray, m1: int, m2: int, noise: str) -> np.ndarray:
    out = np.zeros_like(x, dtype=float)
    for a in range(3):
        for b in range(3):
            out += _C[a] * _C[b] * gamma_phase(x + b * m2 - a * m1, noise)
    return out


def _cross_smooth(x: np.ndarray, m1: int, m2: int) -> np.ndarray:
    """G(x) of the white, flicker and rrw noises at once, shape (3, L) (the hot loop)."""
    out = np.zeros((3, x.size))
    for a in range(3):
        for b in range(3):
            u = np.abs(x + (b * m2 - a * m1))
            c = _C[a] * _C[b]
            with np.errstate(divide="ignore", invalid="ignore"):
                flick = np.where(u == 0, 0.0, u * u * np.log(u))
            out[0] += c * (-0.5 * u)
            out[1] += c * flick
            out[2] += c * (u * u * u - u) / 12.0
    return out


def _lags(m1: int, m2: int, M1: int, M2: int, flicker: bool):
    """Lag grid x = l - i and the weight of each grid point (pair count x stride)."""
    tail = _FLICKER_TAIL * max(m1, m2) if flicker else 0
    lo = max(-(M1 - 1), -2 * m2 - tail)
    hi = min(M2 - 1, 2 * m1 + tail)
    span = hi - lo + 1
    q = max(1, -(-span // _MAX_LAGS))
    x = np.arange(lo, hi + 1, q, dtype=float)
    pairs = np.maximum(0.0, np.minimum(M1, M2 - x) - np.maximum(0.0, -x))
    return x, pairs * q


def covariance_tensors(ms, counts) -> CovTensors:
    """Build :class:`CovTensors` for overlapping AVAR at cluster sizes ``ms`` (term counts
    ``counts``, e.g. ``n + 1 - 2m`` without gaps).

    The tensors depend on the tau grid and the record's length only, so they are kept for
    the last :data:`KEPT_GRIDS` grids: the units of a pool, or the records of a fleet, of one
    length share them (read-only arrays)."""
    return _tensors(tuple(int(m) for m in np.asarray(ms).ravel()),
                    tuple(float(c) for c in np.asarray(counts).ravel()))


#: tau grids whose :func:`covariance_tensors` are kept (each (K, K, 4, 4) floats, ~0.1 MB
#: at K = 25; `fogbayes plan` compares hundreds of candidate lengths)
KEPT_GRIDS = 512


@functools.lru_cache(maxsize=KEPT_GRIDS)
def _tensors(ms: tuple, counts: tuple) -> CovTensors:
    ms = np.asarray(ms, dtype=int)
    counts = np.asarray(counts, dtype=float)
    K, P = ms.size, len(NOISE_TYPES)
    expect = np.stack([expected_avar(ms, p) for p in NOISE_TYPES])
    T = np.zeros((K, K, P, P))
    U = np.zeros((K, K, P))
    for j in range(K):
        for k in range(j, K):
            m1, m2, M1, M2 = int(ms[j]), int(ms[k]), int(counts[j]), int(counts[k])
            x, w = _lags(m1, m2, M1, M2, flicker=True)
            G = np.zeros((len(NOISE_TYPES), x.size))  # (P, L); quantization row set below
            G[1:] = _cross_smooth(x, m1, m2)
            inner = (G * w) @ G.T  # (P, P): sum_x n(x) G_p(x) G_q(x)
            # Quantization G is a comb on the lags a m1 - b m2 that a strided grid can miss:
            # its rows and columns are summed exactly on those lags.
            xs = np.unique([a * m1 - b * m2 for a in range(3) for b in range(3)]).astype(float)
            ws = np.maximum(0.0, np.minimum(M1, M2 - xs) - np.maximum(0.0, -xs))
            Gs = np.stack([_cross(xs, m1, m2, p) for p in NOISE_TYPES])
            exact = (Gs[:1] * ws) @ Gs.T  # (1, P)
            inner[0, :] = inner[:, 0] = exact[0]
            linear = G @ w
            linear[0] = Gs[0] @ ws
            norm = (2.0 * m1 * m1 * M1) * (2.0 * m2 * m2 * M2)
            T[j, k] = T[k, j] = 2.0 / norm * inner
            U[j, k] = U[k, j] = 4.0 * (m1 * m1) * (m2 * m2) / norm * linear
    for a in (ms, counts, expect, T, U):
        a.setflags(write=False)
    return CovTensors(ms, counts, expect, T, U)


def mixture_moments(tensors: CovTensors, scales, ramp=0.0):
    """Mean (K,) and covariance (K, K) of the AVAR estimates for noise ``scales`` (P,) and a
    rate ramp of ``ramp`` per sample (both in the sample units of the module docstring).

    Works on NumPy or JAX arrays (differentiable in ``scales`` and ``ramp``).
    """
    xp = namespace(scales, ramp)
    s = xp.asarray(scales, dtype=float)
    ms = xp.asarray(tensors.ms, dtype=float)
    mean = s @ xp.asarray(tensors.expect) + ramp**2 * ms**2 / 2.0
    cov = xp.einsum("jkpq,p,q->jk", xp.asarray(tensors.T), s, s)
    cov = cov + ramp**2 * xp.einsum("jkp,p->jk", xp.asarray(tensors.U), s)
    return mean, cov


def mixture_edf(tensors: CovTensors, scales) -> np.ndarray:
    """EDF per tau implied by the mixture: ``2 mean^2 / var``."""
    mean, cov = mixture_moments(tensors, scales)
    return np.asarray(2 * mean ** 2 / namespace(cov).diag(cov))
