"""The noise model's profile likelihoods (ML and REML) and their exact gradients, on the CPU.

The same filter and profile as :mod:`fogbayes.inference.noise_ssm` (its ``_negll`` and
:mod:`fogbayes.loop.reml`'s objective are the definitions; the tests hold these to them),
with the gradient by forward sensitivities: each step carries dA/dtheta_i and dP/dtheta_i beside
A and P. theta has 2-6 entries, so this costs a few forward passes and no reverse pass; a Numba
loop does it in a fraction of the time XLA's scan of value and gradient takes on a small state,
and compiles once for every record length and design width (no padding).

Profiled out at theta (g_t = m_t / F_t, v_t = innovations of [y, X], gamma = [1, -beta]):
r_t = v_t' gamma, RSS = sum g r^2. By the envelope theorem beta's change does not enter the
derivative at the optimum: dRSS_i = sum (dg_i r^2 + 2 g r dv_i' gamma), dg_i = -m dF_i / F^2.
ML: -log L = 1/2 [n log(2 pi RSS / n) + sum m log F + n].
REML (n - p in place of n, plus log det S_XX): d log det S_XX = tr(S_XX^-1 dS_XX_i).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.linalg import solve_triangular

from ..support.numba_cache import numba

# ``spec`` below is a noise_ssm.NoiseSpec (not imported: noise_ssm filters with this module)


def system_and_derivatives(spec: NoiseSpec, theta) -> tuple[np.ndarray, ...]:
    """``noise_ssm.system``'s (phi, q, p0), each (d,), and their derivatives (k, d) in theta
    (the order of ``noise_ssm.unpack``: log flicker, log walk, Markov log variances, log taus)."""
    theta = np.asarray(theta, float)
    k = theta.size
    phis, qs, p0s = [], [], []
    dphi, dq, dp0 = [], [], []  # blocks of columns, one per part, (k, d_part)
    i = 0
    if spec.bank_taus:
        tb = np.asarray(spec.bank_taus, float)
        v = math.exp(theta[i])
        c = -np.expm1(-2.0 * spec.dt / tb)
        phis.append(np.exp(-spec.dt / tb))
        qs.append(v * c)
        p0s.append(np.full(tb.size, v))
        z = np.zeros((k, tb.size))
        dphi.append(z)
        dq.append(_row(k, i, v * c))
        dp0.append(_row(k, i, np.full(tb.size, v)))
        i += 1
    i_rw = i if spec.random_walk else None
    i += int(spec.random_walk)
    m = spec.n_markov
    if m:
        lv, lt = theta[i:i + m], theta[i + m:i + 2 * m]
        v, tau = np.exp(lv), np.exp(lt)
        ph = np.exp(-spec.dt / tau)
        e2 = np.exp(-2.0 * spec.dt / tau)
        c = -np.expm1(-2.0 * spec.dt / tau)
        phis.append(ph)
        qs.append(v * c)
        p0s.append(v)
        a, b, c_ = (np.zeros((k, m)) for _ in range(3))
        for j in range(m):
            a[i + m + j, j] = ph[j] * spec.dt / tau[j]         # dphi / dlog tau
            b[i + j, j] = v[j] * c[j]                          # dq / dlog var
            b[i + m + j, j] = -v[j] * e2[j] * 2.0 * spec.dt / tau[j]  # dq / dlog tau
            c_[i + j, j] = v[j]                                # dp0 / dlog var
        dphi.append(a)
        dq.append(b)
        dp0.append(c_)
    if spec.random_walk:
        qrw = math.exp(theta[i_rw])
        phis.append(np.ones(1))
        qs.append(np.array([qrw]))
        p0s.append(np.zeros(1))
        dphi.append(np.zeros((k, 1)))
        dq.append(_row(k, i_rw, np.array([qrw])))
        dp0.append(np.zeros((k, 1)))
    if not phis:
        z = np.zeros(0)
        return z, z, z, np.zeros((k, 0)), np.zeros((k, 0)), np.zeros((k, 0))
    return (np.concatenate(phis), np.concatenate(qs), np.concatenate(p0s),
            np.hstack(dphi), np.hstack(dq), np.hstack(dp0))


def system(spec: NoiseSpec, theta) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``noise_ssm.system``'s (phi, q, p0) at ``theta``, in NumPy."""
    return system_and_derivatives(spec, theta)[:3]


def _row(k: int, i: int, values: np.ndarray) -> np.ndarray:
    out = np.zeros((k, values.size))
    out[i] = values
    return out


@numba.njit(cache=True, nogil=True)
def _filter(phi, q, p0, dphi, dq, dp0, Y, mask, w, V, F, dV, dF, G):  # pragma: no cover (Numba)
    """``noise_ssm._filter`` of every column of Y (n, C), with the sensitivities of its
    innovations V (n, C) and variances F (n,) to each of k parameters: dV (k, n, C), dF (k, n).
    k = 0 gives the filter alone; G (n, d), unless it has no rows, receives the gains k_t
    (they and F do not depend on the data: C = 0 runs the covariance recursion alone)."""
    n, C = Y.shape
    d = phi.size
    K = dq.shape[0]
    A = np.zeros((d, C))
    P = np.zeros((d, d))
    dA = np.zeros((K, d, C))
    dP = np.zeros((K, d, d))
    for a in range(d):
        P[a, a] = p0[a]
        for i in range(K):
            dP[i, a, a] = dp0[i, a]
    Pz = np.zeros(d)
    kg = np.zeros(d)
    v = np.zeros(C)
    dPz = np.zeros((K, d))
    dkg = np.zeros((K, d))
    dv = np.zeros((K, C))
    gains = G.shape[0] > 0
    Pf = np.zeros((d, d))
    for t in range(n):
        m = mask[t]
        Ft = w[t]
        for a in range(d):
            s = 0.0
            for b in range(d):
                s += P[a, b]
            Pz[a] = s
            Ft += s
        for c in range(C):
            s = 0.0
            for a in range(d):
                s += A[a, c]
            v[c] = Y[t, c] - s
            V[t, c] = v[c]
        F[t] = Ft
        for a in range(d):
            kg[a] = Pz[a] / Ft
            if gains:
                G[t, a] = kg[a]
        for i in range(K):
            f = 0.0
            for a in range(d):
                s = 0.0
                for b in range(d):
                    s += dP[i, a, b]
                dPz[i, a] = s
                f += s
            dF[i, t] = f
            for c in range(C):
                s = 0.0
                for a in range(d):
                    s += dA[i, a, c]
                dv[i, c] = -s
                dV[i, t, c] = -s
            for a in range(d):
                dkg[i, a] = (dPz[i, a] * Ft - Pz[a] * f) / (Ft * Ft)
        # measurement update, then the time update; sensitivities first (they read A, P)
        for i in range(K):
            for a in range(d):
                for c in range(C):
                    dAf = dA[i, a, c] + m * (dkg[i, a] * v[c] + kg[a] * dv[i, c])
                    Af = A[a, c] + m * kg[a] * v[c]
                    dA[i, a, c] = dphi[i, a] * Af + phi[a] * dAf
            for a in range(d):
                for b in range(d):
                    dPf = dP[i, a, b] - m * (dkg[i, a] * Pz[b] + kg[a] * dPz[i, b])
                    Pfab = P[a, b] - m * kg[a] * Pz[b]
                    Pf[a, b] = (dphi[i, a] * Pfab * phi[b] + phi[a] * dPf * phi[b]
                                + phi[a] * Pfab * dphi[i, b])
            for a in range(d):
                for b in range(a, d):
                    s = 0.5 * (Pf[a, b] + Pf[b, a])
                    dP[i, a, b] = s
                    dP[i, b, a] = s
                dP[i, a, a] += dq[i, a]
        for a in range(d):
            for c in range(C):
                A[a, c] = phi[a] * (A[a, c] + m * kg[a] * v[c])
        for a in range(d):
            for b in range(d):
                Pf[a, b] = phi[a] * (P[a, b] - m * kg[a] * Pz[b]) * phi[b]
        for a in range(d):
            for b in range(a, d):
                s = 0.5 * (Pf[a, b] + Pf[b, a])
                P[a, b] = s
                P[b, a] = s
            P[a, a] += q[a]


def innovations(spec: NoiseSpec, theta, Y, mask, w, grad: bool = True):
    """V (n, C), F (n,) of Y under ``theta``; with ``grad`` also dV (k, n, C), dF (k, n)."""
    phi, q, p0, dphi, dq, dp0 = system_and_derivatives(spec, theta)
    if not grad:
        dphi, dq, dp0 = (np.zeros((0, phi.size)) for _ in range(3))
    Y = np.ascontiguousarray(Y, dtype=float)
    n, C = Y.shape
    K = dq.shape[0]
    V, F = np.empty((n, C)), np.empty(n)
    dV, dF = np.empty((K, n, C)), np.empty((K, n))
    _filter(phi, q, p0, np.ascontiguousarray(dphi), np.ascontiguousarray(dq),
            np.ascontiguousarray(dp0), Y, np.asarray(mask, float), np.asarray(w, float),
            V, F, dV, dF, np.empty((0, phi.size)))
    return V, F, dV, dF


def negloglik(spec: NoiseSpec, theta, y, X, mask, w, *, reml: bool = False,
              grad: bool = True) -> tuple[float, np.ndarray]:
    """-log L (profile ML, or REML with ``reml``) of y on X under ``theta`` and its gradient
    (zeros without ``grad``); NaN where S_XX is singular or a variance is not positive."""
    mask = np.asarray(mask, float)
    X = np.asarray(X, float)
    Y = np.where(mask[:, None] > 0, np.column_stack([y, X]), 0.0)  # a missing block's y: NaN
    k = np.size(theta)
    with np.errstate(all="ignore"):
        V, F, dV, dF = innovations(spec, theta, Y, mask, w, grad)
        g = mask / F
        Vx = V[:, 1:]
        Sxx = (Vx * g[:, None]).T @ Vx
        try:
            L = np.linalg.cholesky(Sxx)
        except np.linalg.LinAlgError:
            return float("nan"), np.full(k, np.nan)
        beta = _cho_solve(L, Vx.T @ (g * V[:, 0]))
        r = V[:, 0] - Vx @ beta  # from the residual (noise_ssm's module doc, "Precision")
        rss = float(np.sum(g * r * r))
        n = float(mask.sum()) - (X.shape[1] if reml else 0)
        val = 0.5 * (n * math.log(2 * math.pi * rss / n) + float(np.sum(mask * np.log(F))) + n)
        if reml:
            val += float(np.sum(np.log(np.diag(L))))  # 1/2 log det S_XX
        if not grad:
            return val, np.zeros(k)
        dg = -mask * dF / (F * F)  # (k, n)
        dr = dV[:, :, 0] - dV[:, :, 1:] @ beta
        drss = dg @ (r * r) + 2.0 * (dr @ (g * r))
        gr = 0.5 * (n * drss / rss + dF @ (mask / F))
        if reml:  # 1/2 tr(S_XX^-1 dS_XX_i)
            H = _cho_solve(L, Vx.T).T  # Vx S_XX^-1 (n, p)
            quad = np.sum(H * Vx, axis=1)
            cross = np.einsum("np,knp->kn", H, dV[:, :, 1:])
            gr = gr + 0.5 * (dg @ quad + 2.0 * (cross @ g))
    return val, gr


def _cho_solve(L: np.ndarray, b: np.ndarray) -> np.ndarray:
    return solve_triangular(L.T, solve_triangular(L, b, lower=True), lower=False)


@numba.njit(cache=True, nogil=True)
def _adjoint(phi, K, F, mask, Z, out):  # pragma: no cover (Numba)
    """out = W' Z for the whitening map W: y -> m v / sqrt(F) (v_t = m_t y_t - 1'A_t,
    A_{t+1} = phi (A_t + m_t k_t v_t)), by the reverse recursion with lam = dL/dA_{t+1}:
    vbar_t = Z_t m_t / sqrt(F_t) + m_t (phi k_t)' lam, ybar_t = m_t vbar_t,
    lam <- phi lam - 1 vbar_t."""
    n, C = Z.shape
    d = phi.size
    lam = np.zeros((d, C))
    for t in range(n - 1, -1, -1):
        m = mask[t]
        sc = m / np.sqrt(F[t])
        for c in range(C):
            vb = Z[t, c] * sc
            if m != 0.0:
                s = 0.0
                for a in range(d):
                    s += phi[a] * K[t, a] * lam[a, c]
                vb += m * s
            out[t, c] = m * vb
            for a in range(d):
                lam[a, c] = phi[a] * lam[a, c] - vb


def whiten_transpose(spec: NoiseSpec, theta, Z, mask, w) -> np.ndarray:
    """L^-T Z (n, C): the transpose of ``noise_ssm.whiten``'s linear map (the filter's gains
    do not depend on the data), so L^-T (L^-1 X) = S^-1 X, what a GLS estimate's sandwich
    needs."""
    phi, q, p0 = system(spec, theta)
    mask = np.asarray(mask, float)
    n, d = mask.size, phi.size
    K, F = np.empty((n, d)), np.empty(n)
    none = np.zeros((0, d))
    _filter(phi, q, p0, none, none, none, np.empty((n, 0)), mask, np.asarray(w, float),
            np.empty((n, 0)), F, np.empty((0, n, 0)), np.empty((0, n)), K)
    Z = np.ascontiguousarray(Z, dtype=float)
    out = np.empty_like(Z)
    _adjoint(phi, K, F, mask, Z, out)
    return out

