"""A held-out fold's predictive density when the added term has a searched parameter (a step's time).

Each fold averages over the grid g with the weights of its training blocks (flat priors):
w_g ∝ exp(-RSS_g / (2 s2)) / sqrt(c_g), lpd_k = log sum_g w_g p(y_k | y_(-k); beta_g). From the
Gram S = V' diag(m / F) V of [y, model, grid] with K = S_bb^-1 S_bg, k = S_bb^-1 S_by:
c_g = S_gg - S_bg'K_g, beta_g = (S_gy - S_bg'k) / c_g, RSS_g = S_yy - S_by'k - c_g beta_g^2;
c_g ~ 0 gets no weight.
"""

from __future__ import annotations

import math

import numpy as np


def _gram(V: np.ndarray, F: np.ndarray, m: np.ndarray, p: int):
    """Gram blocks of [y, b (columns 1..p-1), grid (columns p..)] weighted by m / F."""
    g = m / F
    Vyb = V[:, :p]
    A = V[:, p:]
    S = (Vyb * g[:, None]).T @ Vyb                   # (p, p): [y, b] x [y, b]
    SA = (Vyb * g[:, None]).T @ A                    # (p, G): [y, b] x grid
    dA = np.einsum("i,ij,ij->j", g, A, A)            # (G,): grid columns with themselves
    return S, SA, dA


def _quad(S, SA, dA, bb: np.ndarray, bg: np.ndarray) -> np.ndarray:
    """sum m/F (v_y - V_b bb_g - v_g bg_g)^2 for every g (bb: (B, G), bg: (G,))."""
    Syy, Sby, Sbb = S[0, 0], S[1:, 0], S[1:, 1:]
    SAy, SbA = SA[0], SA[1:]
    return (Syy - 2.0 * (Sby @ bb) - 2.0 * bg * SAy + np.einsum("bg,bc,cg->g", bb, Sbb, bb)
            + 2.0 * bg * np.einsum("bg,bg->g", bb, SbA) + bg * bg * dA)


def fold_lpd(V: np.ndarray, F: np.ndarray, train: np.ndarray, V_all: np.ndarray,
             F_all: np.ndarray, obs: np.ndarray, p: int, s2: float) -> float:
    """lpd_k of the module doc. V, F: innovations of [y, rest (p - 1 columns), grid (G)]
    filtered with the fold held out (mask ``train``); V_all, F_all: the same on the full
    mask ``obs``; s2: the fit's white variance."""
    S, SA, dA = _gram(V, F, train, p)
    Sbb, Sby, SbA = S[1:, 1:], S[1:, 0], SA[1:]
    try:
        L = np.linalg.cholesky(Sbb)
        K = np.linalg.solve(L.T, np.linalg.solve(L, SbA))
        k = np.linalg.solve(L.T, np.linalg.solve(L, Sby))
    except np.linalg.LinAlgError:  # the rest is collinear on these blocks (as profile_np)
        inv = np.linalg.pinv(Sbb, hermitian=True)
        K, k = inv @ SbA, inv @ Sby
    c = dA - np.einsum("bg,bg->g", SbA, K)
    ok = c > 1e-10 * max(float(np.max(dA, initial=0.0)), 1e-300)
    c = np.where(ok, c, 1.0)
    bg = (SA[0] - SbA.T @ k) / c
    bb = k[:, None] - K * bg[None, :]
    rss = S[0, 0] - Sby @ k - c * bg * bg
    log_w = np.where(ok, -0.5 * rss / s2 - 0.5 * np.log(c), -np.inf)
    S1, SA1, dA1 = _gram(V_all, F_all, obs, p)
    held = -0.5 * (_quad(S1, SA1, dA1, bb, bg) - _quad(S, SA, dA, bb, bg)) / s2
    const = (-0.5 * float(np.sum(obs * np.log(2.0 * math.pi * s2 * F_all)))
             + 0.5 * float(np.sum(train * np.log(2.0 * math.pi * s2 * F))))
    return const + _logsumexp(log_w[ok] + held[ok]) - _logsumexp(log_w[ok])


def _logsumexp(a: np.ndarray) -> float:
    top = float(np.max(a))
    return top + math.log(float(np.sum(np.exp(a - top))))
