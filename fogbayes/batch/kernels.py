r"""Compiled per-sensor loops of the vectorised fit (Numba, CPU; sensors on all cores).

Each kernel does for every sensor ``s`` (``prange``) what the per-recording workflow does
with NumPy, in one pass over that sensor's samples, never building the (sensors, samples,
terms) design array that a batched XLA program has to stream through memory:

* :func:`fit_gram` -- weighted least squares by the normal equations in the sensor's own
  scaled basis (:func:`fogbayes.inference.lsq.lstsq_gram`'s equations)::

      z'_i = (z_i - centre_s) / scale_s,     x_ik = prod_c z'_ic ** e_kc
      G = sum_i w_i x_i x_i^T,   g = sum_i w_i y_i x_i,   G = L L^T (Cholesky)
      b = G^{-1} g,   s^2 = sum_i w_i (y_i - x_i b)^2 / (m_s - p),   Cov = s^2 G^{-1}

  a fit is ``ok`` when ``min diag L > rcond * max diag L`` (the QR path's rank test on
  ``R``, since ``diag L = |diag R|``) and ``m_s > p``;
* :func:`evaluate` -- the modelled bias ``x(z_i) . b`` at every sample;
* :func:`pauta` -- :func:`fogbayes.preprocess.pauta_flags` on each row: passes of
  ``|r_i - mean| > n_sigma * std_{n-1}`` over the samples not yet flagged, until a pass
  flags nothing new;
* :func:`masked_block_means` -- block means of rate and covariates without the flagged
  samples (:func:`fogbayes.preprocess.blocks.group_mean`'s definition, one shared clock).

Sums run in sample order (NumPy sums pairwise), so results agree with the NumPy path to
rounding, ~1e-15 relative (tests/test_batch_kernels.py). Covariates are stored
covariate-major, z (S, c, n): each covariate of a sensor is one contiguous row, as the
per-sensor min/max and the block means read them. ``cache=True``: the machine code is
stored beside this file, so only a first process pays the compilation.
"""

from __future__ import annotations

import numba
import numpy as np
from numba import prange


@numba.njit(cache=True, inline="always")
def _row(z, s, i, centre, scale, exps, x):
    """Monomials of sample i of sensor s (z (S, c, n)) in its scaled basis, into x (p,)."""
    p, c = exps.shape
    for k in range(p):
        x[k] = 1.0
    for j in range(c):
        u = (z[s, j, i] - centre[s, j]) / scale[s, j]
        for k in range(p):
            for _ in range(exps[k, j]):  # integer powers by products (no pow call)
                x[k] *= u


@numba.njit(cache=True, parallel=True)
def fit_gram(z, y, w, centre, scale, n_valid, exps, rcond):
    """Weighted LSQ of every sensor. z (S, c, m), y, w (S, m), centre/scale (S, c),
    n_valid (S,) rows that count for the dof, exps (p, c) int. Rows of weight 0 are skipped
    (their values may be NaN) and get a NaN residual.

    Returns coef (S, p), cov (S, p, p), resid (S, m), s2 (S,), dof (S,), ok (S,) bool.
    """
    S, m = y.shape
    p = exps.shape[0]
    coef = np.zeros((S, p))
    cov = np.zeros((S, p, p))
    resid = np.zeros((S, m))
    s2 = np.zeros(S)
    dof = np.zeros(S)
    ok = np.zeros(S, np.bool_)
    for s in prange(S):
        x = np.empty(p)
        G = np.zeros((p, p))
        g = np.zeros(p)
        for i in range(m):
            wi = w[s, i]
            if wi == 0.0:  # an empty or padding block (NaN values): not a row of this fit
                continue
            _row(z, s, i, centre, scale, exps, x)
            for a in range(p):
                wxa = wi * x[a]
                g[a] += wxa * y[s, i]
                for b in range(a + 1):
                    G[a, b] += wxa * x[b]
        L = np.zeros((p, p))  # Cholesky, lower
        good = True
        for a in range(p):
            for b in range(a + 1):
                acc = G[a, b]
                for k in range(b):
                    acc -= L[a, k] * L[b, k]
                if a == b:
                    if not acc > 0.0:
                        good = False
                        acc = 0.0
                    L[a, a] = np.sqrt(acc)
                else:
                    L[a, b] = acc / L[b, b] if L[b, b] > 0.0 else np.nan
        dmin, dmax = np.inf, 0.0
        for a in range(p):
            dmin = min(dmin, abs(L[a, a]))
            dmax = max(dmax, abs(L[a, a]))
        Linv = np.zeros((p, p))  # inverse of L by forward substitution
        for col in range(p):
            Linv[col, col] = 1.0 / L[col, col]
            for a in range(col + 1, p):
                acc = 0.0
                for k in range(col, a):
                    acc -= L[a, k] * Linv[k, col]
                Linv[a, col] = acc / L[a, a]
        Ginv = Linv.T @ Linv
        beta = Ginv @ g
        wrss = 0.0
        for i in range(m):
            if w[s, i] == 0.0:
                resid[s, i] = np.nan
                continue
            _row(z, s, i, centre, scale, exps, x)
            f = 0.0
            for a in range(p):
                f += x[a] * beta[a]
            r = y[s, i] - f
            resid[s, i] = r
            wrss += w[s, i] * r * r
        d = n_valid[s] - p
        var = wrss / max(d, 1.0)
        coef[s] = beta
        cov[s] = var * Ginv
        s2[s] = var
        dof[s] = d
        finite = True
        for a in range(p):
            finite = finite and np.isfinite(beta[a])
        ok[s] = good and dmin > rcond * dmax and d > 0 and finite
    return coef, cov, resid, s2, dof, ok


@numba.njit(cache=True, parallel=True)
def evaluate(coef, z, centre, scale, exps):
    """x(z_si) . b_s for every sensor s and sample i: coef (S, p), z (S, c, n) -> (S, n)."""
    S, n = z.shape[0], z.shape[2]
    p = exps.shape[0]
    out = np.empty((S, n))
    for s in prange(S):
        x = np.empty(p)
        for i in range(n):
            _row(z, s, i, centre, scale, exps, x)
            f = 0.0
            for a in range(p):
                f += x[a] * coef[s, a]
            out[s, i] = f
    return out


@numba.njit(cache=True, parallel=True)
def pauta(r, n_sigma, max_iter):
    """Iterated n-sigma flags of each row of r (S, n): mask (S, n), count (S,),
    threshold (S,), passes (S,) -- ``pauta_flags(r[s], n_sigma=..., max_iter=...)``."""
    S, n = r.shape
    mask = np.zeros((S, n), np.bool_)
    count = np.zeros(S, np.int64)
    threshold = np.full(S, np.inf)
    passes = np.zeros(S, np.int64)
    for s in prange(S):
        flagged = 0
        for it in range(1, max_iter + 1):
            passes[s] = it
            k = n - flagged
            if k < 3:
                break
            tot = 0.0
            for i in range(n):
                if not mask[s, i]:
                    tot += r[s, i]
            mean = tot / k
            ss = 0.0
            for i in range(n):
                if not mask[s, i]:
                    d = r[s, i] - mean
                    ss += d * d
            thr = n_sigma * np.sqrt(ss / (k - 1))
            threshold[s] = thr
            new = 0
            for i in range(n):  # decide on the pass's own mean/threshold, then flag
                if not mask[s, i] and abs(r[s, i] - mean) > thr:
                    new += 1
            if new == 0:
                break
            for i in range(n):
                if not mask[s, i] and abs(r[s, i] - mean) > thr:
                    mask[s, i] = True
            flagged += new
        count[s] = flagged
    return mask, count, threshold, passes


@numba.njit(cache=True, parallel=True)
def masked_block_means(t, y, z, use, start, stop):
    """Per sensor and block [start_j, stop_j) of the shared time stamps t (n,): mean time of
    the used samples (of all of them where none is used), mean of y (S, n) and of each
    covariate of z (S, c, n) over the used samples (NaN where none is), and their count.

    Returns tm (S, m), y (S, m), z (S, c, m), count (S, m) -- ``fit_blocks``' fields.
    """
    S, c = z.shape[0], z.shape[1]
    nb = start.size
    tm = np.empty((S, nb))
    ym = np.empty((S, nb))
    zm = np.empty((S, c, nb))
    cnt = np.zeros((S, nb), np.int64)
    for s in prange(S):
        acc = np.empty(c)
        for j in range(nb):
            a, b = start[j], stop[j]
            t0 = t[a]
            k = 0
            dt_used = 0.0
            dt_all = 0.0
            ysum = 0.0
            acc[:] = 0.0
            for i in range(a, b):
                rel = t[i] - t0  # offsets from the block's first stamp: no Unix-time rounding
                dt_all += rel
                if use[s, i]:
                    k += 1
                    dt_used += rel
                    ysum += y[s, i]
                    for q in range(c):
                        acc[q] += z[s, q, i]
            cnt[s, j] = k
            tm[s, j] = t0 + (dt_used / k if k > 0 else dt_all / (b - a))
            ym[s, j] = ysum / k if k > 0 else np.nan
            for q in range(c):
                zm[s, q, j] = acc[q] / k if k > 0 else np.nan
    return tm, ym, zm, cnt
