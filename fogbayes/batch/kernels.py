"""Compiled per-sensor loops of the vectorised fit (Numba, CPU; sensors on all cores).

:func:`fit_gram`: in the sensor's scaled basis, G = sum w x x', g = sum w y x, G = LL',
b = G^-1 g, s^2 = sum w (y - x b)^2 / (m_s - p), Cov = s^2 G^-1; ``ok`` when
min diag L > rcond max diag L and m_s > p (:func:`fogbayes.inference.lsq.lstsq_gram`).
:func:`evaluate` (clamped bias), :func:`covariate_range`, :func:`pauta`
(:func:`fogbayes.preprocess.pauta_flags`) and :func:`residual_pauta`. Sums in sample order;
covariates stored (S, c, n); range loops over :func:`fogbayes.support.numba_cache.over_rows`.
"""

from __future__ import annotations

import numpy as np

from ..support.numba_cache import numba, over_rows

CHUNK = 256  # rows of the design built at a time: (p, CHUNK) stays in L1


@numba.njit(cache=True, error_model="numpy", inline="always")
def _monomials(z, s, i0, n, centre, scale, lo, hi, exps, X, u):
    """Monomials of rows i0:i0+n of sensor s into X[:, :n]: each covariate clamped to
    [lo_sj, hi_sj], scaled (z - centre) / scale into u, raised by repeated products."""
    p, c = exps.shape
    for k in range(p):
        for r in range(n):
            X[k, r] = 1.0
    for j in range(c):
        cj, sj, a, b = centre[s, j], scale[s, j], lo[s, j], hi[s, j]
        for r in range(n):
            u[r] = (min(max(z[s, j, i0 + r], a), b) - cj) / sj
        for k in range(p):
            for _ in range(exps[k, j]):  # integer powers by products (no pow call)
                for r in range(n):
                    X[k, r] *= u[r]


@numba.njit(cache=True, error_model="numpy", inline="always")
def _design_chunk(z, w, y, s, i0, n, centre, scale, lo, hi, exps, X, wy):
    """Rows i0:i0+n of sensor s: monomials into X[:, :n] and (weight, y) into wy[:2, :n]
    (wy[2] is scratch); weight-0 rows (values may be NaN) become zeros: they add nothing."""
    p = exps.shape[0]
    _monomials(z, s, i0, n, centre, scale, lo, hi, exps, X, wy[2])
    for r in range(n):
        wr = w[s, i0 + r]
        if wr == 0.0:  # an empty or padding block: not a row of this fit
            wy[0, r] = 0.0
            wy[1, r] = 0.0
            for k in range(p):
                X[k, r] = 0.0
        else:
            wy[0, r] = wr
            wy[1, r] = y[s, i0 + r]


@numba.njit(cache=True, error_model="numpy", fastmath={"reassoc", "contract"})
def _fit_one(z, y, w, centre, scale, n_valid, exps, rcond, lo, hi, s, coef, cov, rss, s2, dof, ok):
    """:func:`fit_gram` of sensor ``s``, written into row ``s`` of its outputs.

    Products and stores are element by element: ``@`` and slice stores (``coef[s] = beta``)
    would compile BLAS calls and Numba's shape-mismatch message (~9 s more on first use)."""
    m = y.shape[1]
    p = exps.shape[0]
    X = np.empty((p, CHUNK))
    wy = np.empty((3, CHUNK))
    wx = np.empty(CHUNK)
    G = np.zeros((p, p))
    g = np.zeros(p)
    for i0 in range(0, m, CHUNK):
        n = min(CHUNK, m - i0)
        _design_chunk(z, w, y, s, i0, n, centre, scale, lo, hi, exps, X, wy)
        for a in range(p):
            acc = 0.0
            for r in range(n):
                wx[r] = wy[0, r] * X[a, r]
                acc += wx[r] * wy[1, r]
            g[a] += acc
            for b in range(a + 1):
                acc = 0.0
                for r in range(n):
                    acc += wx[r] * X[b, r]
                G[a, b] += acc
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
    Ginv = np.zeros((p, p))  # Linv^T Linv
    for a in range(p):
        for b in range(p):
            acc = 0.0
            for k in range(max(a, b), p):
                acc += Linv[k, a] * Linv[k, b]
            Ginv[a, b] = acc
    beta = np.zeros(p)  # Ginv g
    for a in range(p):
        acc = 0.0
        for b in range(p):
            acc += Ginv[a, b] * g[b]
        beta[a] = acc
    wrss = 0.0
    ss = 0.0
    for i0 in range(0, m, CHUNK):
        n = min(CHUNK, m - i0)
        _design_chunk(z, w, y, s, i0, n, centre, scale, lo, hi, exps, X, wy)
        for r in range(n):
            wx[r] = wy[1, r]
        for a in range(p):
            for r in range(n):
                wx[r] -= X[a, r] * beta[a]
        for r in range(n):
            wrss += wy[0, r] * wx[r] * wx[r]
            ss += wx[r] * wx[r]  # weight-0 rows have y = X = 0 here: they add 0
    d = n_valid[s] - p
    var = wrss / max(d, 1.0)
    rss[s] = ss
    for a in range(p):
        coef[s, a] = beta[a]
        for b in range(p):
            cov[s, a, b] = var * Ginv[a, b]
    s2[s] = var
    dof[s] = d
    finite = True
    for a in range(p):
        finite = finite and np.isfinite(beta[a])
    ok[s] = good and dmin > rcond * dmax and d > 0 and finite


@numba.njit(cache=True, error_model="numpy", nogil=True)
def _fit_range(s0, s1, z, y, w, centre, scale, n_valid, exps, rcond, lo, hi,
               coef, cov, rss, s2, dof, ok):
    for s in range(s0, s1):
        _fit_one(z, y, w, centre, scale, n_valid, exps, rcond, lo, hi, s,
                 coef, cov, rss, s2, dof, ok)


def fit_gram(z, y, w, centre, scale, n_valid, exps, rcond):
    """Weighted LSQ of every sensor. z (S, c, m), y, w (S, m), centre/scale (S, c),
    n_valid (S,) rows that count for the dof, exps (p, c) int. Rows of weight 0 are skipped
    (their values may be NaN).

    Returns coef (S, p), cov (S, p, p), rss (S,) (the unweighted residual sum of squares
    over the rows of weight > 0, for the RMS criterion), s2 (S,), dof (S,), ok (S,) bool.
    """
    S, m = y.shape
    p = exps.shape[0]
    lo = np.full(centre.shape, -np.inf)  # no clamping in the fit
    hi = np.full(centre.shape, np.inf)
    coef = np.zeros((S, p))
    cov = np.zeros((S, p, p))
    rss = np.zeros(S)
    s2 = np.zeros(S)
    dof = np.zeros(S)
    ok = np.zeros(S, np.bool_)
    over_rows(_fit_range, S, z, y, w, centre, scale, n_valid, exps, float(rcond), lo, hi,
                  coef, cov, rss, s2, dof, ok)
    return coef, cov, rss, s2, dof, ok


@numba.njit(cache=True, error_model="numpy", fastmath={"reassoc", "contract"})
def _bias_row(coef, z, s, centre, scale, lo, hi, exps, out):
    """x(clip(z_si, lo_s, hi_s)) . b_s for every sample i of sensor s, into out (n,)."""
    n, p = z.shape[2], exps.shape[0]
    X = np.empty((p, CHUNK))
    u = np.empty(CHUNK)
    for i0 in range(0, n, CHUNK):
        k = min(CHUNK, n - i0)
        _monomials(z, s, i0, k, centre, scale, lo, hi, exps, X, u)
        for r in range(k):
            u[r] = 0.0
        for a in range(p):
            for r in range(k):
                u[r] += X[a, r] * coef[s, a]
        for r in range(k):
            out[i0 + r] = u[r]


@numba.njit(cache=True, error_model="numpy", nogil=True)
def _evaluate_range(s0, s1, coef, z, centre, scale, exps, lo, hi, out):
    for s in range(s0, s1):
        _bias_row(coef, z, s, centre, scale, lo, hi, exps, out[s])


def evaluate(coef, z, centre, scale, exps, lo, hi):
    """x(clip(z_si, lo_s, hi_s)) . b_s for every sensor s and sample i: coef (S, p),
    z (S, c, n), lo/hi (S, c) (pass -inf/inf not to clamp) -> (S, n)."""
    S, n = z.shape[0], z.shape[2]
    out = np.empty((S, n))
    over_rows(_evaluate_range, S, coef, z, centre, scale, exps, lo, hi, out)
    return out


@numba.njit(cache=True, error_model="numpy")
def _pauta_row(r, mask, n_sigma, max_iter):
    """``pauta_flags`` of one row r (n,): flags into mask (n,); (count, threshold, passes)."""
    n = r.size
    flagged, thr, passes = 0, np.inf, 0
    for it in range(1, max_iter + 1):
        passes = it
        k = n - flagged
        if k < 3:
            break
        tot = 0.0
        for i in range(n):
            if not mask[i]:
                tot += r[i]
        mean = tot / k
        ss = 0.0
        for i in range(n):
            if not mask[i]:
                d = r[i] - mean
                ss += d * d
        thr = n_sigma * np.sqrt(ss / (k - 1))
        new = 0
        for i in range(n):  # decide on the pass's own mean/threshold, then flag
            if not mask[i] and abs(r[i] - mean) > thr:
                new += 1
        if new == 0:
            break
        for i in range(n):
            if not mask[i] and abs(r[i] - mean) > thr:
                mask[i] = True
        flagged += new
    return flagged, thr, passes


@numba.njit(cache=True, error_model="numpy", nogil=True)
def _pauta_range(s0, s1, r, n_sigma, max_iter, mask, count, threshold, passes):
    for s in range(s0, s1):
        count[s], threshold[s], passes[s] = _pauta_row(r[s], mask[s], n_sigma, max_iter)


def pauta(r, n_sigma, max_iter):
    """Iterated n-sigma flags of each row of r (S, n): mask (S, n), count (S,),
    threshold (S,), passes (S,) -- ``pauta_flags(r[s], n_sigma=..., max_iter=...)``."""
    S, n = r.shape
    mask = np.zeros((S, n), np.bool_)
    count = np.zeros(S, np.int64)
    threshold = np.full(S, np.inf)
    passes = np.zeros(S, np.int64)
    over_rows(_pauta_range, S, r, float(n_sigma), int(max_iter), mask, count, threshold,
                  passes)
    return mask, count, threshold, passes


@numba.njit(cache=True, error_model="numpy", nogil=True)
def _residual_pauta_range(s0, s1, y, coef, z, centre, scale, exps, n_sigma, max_iter, lo, hi,
                          mask, count):
    n = y.shape[1]
    r = np.empty(n)
    for s in range(s0, s1):
        _bias_row(coef, z, s, centre, scale, lo, hi, exps, r)
        for i in range(n):
            r[i] = y[s, i] - r[i]
        count[s] = _pauta_row(r, mask[s], n_sigma, max_iter)[0]


def residual_pauta(y, coef, z, centre, scale, exps, n_sigma, max_iter):
    """:func:`pauta` of the residuals ``y - x(z) . b`` of every sensor (y (S, n)), each
    formed in a per-thread buffer: mask (S, n) and count (S,)."""
    S, n = y.shape
    lo = np.full(centre.shape, -np.inf)
    hi = np.full(centre.shape, np.inf)
    mask = np.zeros((S, n), np.bool_)
    count = np.zeros(S, np.int64)
    over_rows(_residual_pauta_range, S, y, coef, z, centre, scale, exps, float(n_sigma),
                  int(max_iter), lo, hi, mask, count)
    return mask, count


@numba.njit(cache=True, error_model="numpy", nogil=True)
def _range_range(s0, s1, z, w, lo, hi):
    c, m = z.shape[1], z.shape[2]
    for s in range(s0, s1):
        for j in range(c):
            a, b = np.inf, -np.inf
            for i in range(m):
                if w[s, i] > 0.0:
                    v = z[s, j, i]
                    a = min(a, v)
                    b = max(b, v)
            lo[s, j], hi[s, j] = a, b


def covariate_range(z, w):
    """Min and max of each covariate of z (S, c, m) over the rows with w (S, m) > 0."""
    S, c = z.shape[0], z.shape[1]
    lo = np.full((S, c), np.inf)
    hi = np.full((S, c), -np.inf)
    over_rows(_range_range, S, z, w, lo, hi)
    return lo, hi
