"""Evidence for adding a candidate effect under coloured noise.

With noise fixed at the current fit, the Kalman filter whitens y, X and each candidate Z_g:
stat_g = ||Q_g' r||^2 / s2 ~ chi^2_k (Q_g a basis of M Z~_g; ``periodic``: the periodogram,
chi^2_2). The min p over a grid is calibrated by parametric bootstrap under the REML noise
model (:mod:`fogbayes.loop.reml`): P(min p <= u) = 1 - (1 - u)^M_eff; C candidates by
Sidak, p_fw = 1 - (1 - p_c)^C. Acceptance: refitted LR gives p_fw < alpha AND PSIS-LOO ELPD
difference > 0; survivors are ranked by :mod:`fogbayes.loop.compete`.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from scipy import special

from ..support.tails import chi2_logsf
from ..inference import noise_ssm as ns
from . import nullsim
from .candidates import Candidate
from .context import Context
from .fitting import ModelFit
from ..effects.kinds import Periodic
from ..effects.terms import Term, columns

ALPHA = 0.01


class Whitened(NamedTuple):
    """The current model in whitened form (observed blocks only)."""

    spec: ns.NoiseSpec
    theta: np.ndarray
    Qx: np.ndarray        # (n_obs, p) orthonormal basis of the whitened design
    r: np.ndarray         # (n_obs,) whitened GLS residual
    s2: float
    E: np.ndarray         # (n_obs, B) whitened simulated null noise, projected like r
    e_s2: np.ndarray      # (B,) their residual variances


class Screened(NamedTuple):
    """Screening result of one candidate (fixed noise hyperparameters)."""

    candidate: Candidate
    best: Term | None      # grid term with the smallest p (None: spectral / noise)
    best_value: float | None  # the searched value at the optimum (frequency for periodic)
    stat: float            # 2 dlogL of the best grid point
    dof: int
    log_p_min: float       # log of the smallest chi^2 p over the grid
    m_eff: float           # effective number of independent tests (from simulations)
    log_p: float           # calibrated log p-value
    #: calibrated log p under the *fitted* noise model alone, when ``log_p`` is the better of
    #: two looks (:func:`fogbayes.loop.core._screen_all`); None: ``log_p`` is that one
    gate_log_p: float | None = None


def whiten_columns(ctx: Context, spec, theta, Y: np.ndarray | list[np.ndarray]) -> np.ndarray:
    """Whitened (n_obs, c) columns of block-level Y (n_blocks, c) under noise ``theta`` (or of
    a list of (n_blocks, k) arrays side by side, never stacked whole)."""
    W, _ = ns.whiten(spec, theta, Y, ctx.grid.mask, ctx.grid.w)
    obs = ctx.grid.mask > 0
    return W if obs.all() else W[obs]


def whitened_model(ctx: Context, fit: ModelFit, *, n_sims: int, seed: int,
                   extra: np.ndarray | list[np.ndarray] | None = None
                   ) -> tuple[Whitened, np.ndarray | None]:
    """Whiten the model, ``n_sims`` series simulated from its noise model and ``extra`` columns.

    One filter pass for everything (the gains are shared); returns the whitened model and
    the whitened ``extra`` (n_obs, c) block columns (candidate terms; an array or a list of
    (n_blocks, k) arrays, side by side), or None.
    """
    spec, theta = fit.noise.spec, fit.noise.theta
    sims = nullsim.simulate(spec, theta, 1.0, ctx.grid.w, n_sims, seed=seed)
    more = [] if extra is None else list(extra) if isinstance(extra, list) else [extra]
    W = whiten_columns(ctx, spec, theta, [ctx.y[:, None], fit.X, sims] + more)
    p = fit.X.shape[1]
    Qx, _ = np.linalg.qr(W[:, 1:1 + p])
    r = W[:, 0] - Qx @ (Qx.T @ W[:, 0])
    dof = max(W.shape[0] - p, 1)
    E = W[:, 1 + p:1 + p + n_sims]
    E = E - Qx @ (Qx.T @ E)
    wm = Whitened(spec, np.asarray(theta), Qx, r, float(r @ r / dof), E,
                  np.sum(E * E, axis=0) / dof)
    return wm, (W[:, 1 + p + n_sims:] if extra is not None else None)


def _basis(Zw: np.ndarray, Qx: np.ndarray, tol: float = 1e-6) -> np.ndarray | None:
    """Orthonormal basis of the part of whitened Z not explained by the design (or None)."""
    Zp = Zw - Qx @ (Qx.T @ Zw)
    Q, R = np.linalg.qr(Zp)
    scale = np.linalg.norm(Zw, axis=0).max()
    if scale <= 0 or np.min(np.abs(np.diag(R))) < tol * scale:
        return None
    return Q


def _log_sf(stat: np.ndarray, k: int) -> np.ndarray:
    """log P(chi^2_k > stat), finite even where the tail underflows (ranking needs it).

    Beyond scipy's range: log Q(s, y) = (s - 1) log y - y - lgamma(s)
    + log(1 + (s-1)/y + (s-1)(s-2)/y^2), s = k/2, y = stat/2 (asymptotic series).
    """
    x = np.maximum(np.asarray(stat, dtype=float), 0.0)
    if k == 1:  # P(chi2_1 > x) = 2 Phi(-sqrt x): exact, fast and finite everywhere
        return math.log(2.0) + special.log_ndtr(-np.sqrt(x))
    if k == 2:  # P(chi2_2 > x) = exp(-x / 2)
        return -0.5 * x
    out = np.asarray(chi2_logsf(x, k), dtype=float)
    bad = ~np.isfinite(out)
    if np.any(bad):
        s, y = 0.5 * k, 0.5 * np.maximum(x[bad] if x.ndim else x, 1e-300)
        out = np.array(out, copy=True)
        approx = ((s - 1) * np.log(y) - y - special.gammaln(s)
                  + np.log1p((s - 1) / y + (s - 1) * (s - 2) / y ** 2))
        if out.ndim:
            out[bad] = approx
        else:
            out = np.asarray(approx)
    return out


def log_chi2_sf(stat: float, k: int) -> float:
    return float(_log_sf(np.asarray(stat, dtype=float), k))


def _m_eff(log_pmin_sims: np.ndarray, n_grid: int) -> float:
    """M with 1 - (1 - u)^M matching the median of the simulated minimum p-values."""
    if n_grid <= 1:
        return 1.0
    u = float(np.exp(np.median(log_pmin_sims)))
    u = min(max(u, 1e-12), 0.999)
    return float(np.clip(-math.log(2.0) / math.log1p(-u), 1.0, 10.0 * n_grid))


def calibrated_log_p(log_pmin: float, m_eff: float) -> float:
    """log(1 - (1 - p)^M) evaluated stably."""
    p = min(math.exp(log_pmin), 1.0 - 1e-16)
    if p < 1e-8:
        return math.log(m_eff) + log_pmin
    return math.log(-math.expm1(m_eff * math.log1p(-p)))


def candidate_columns(ctx: Context, cand: Candidate) -> list[np.ndarray]:
    """Block-level columns of every grid term of a linear candidate."""
    return [columns(tm, ctx.bcov) for tm in cand.grid]


#: one-column grid points screened per matrix product in :func:`_grid_stats`
GRID_CHUNK = 256


def _grid_stats(wm: Whitened, Zw: np.ndarray, ks: list[int], tol: float = 1e-6):
    """2 dlogL of each grid point (data and simulations); None where not identifiable.

    One-column grid points (most) are done together, :data:`GRID_CHUNK` at a time: normalise
    the design-orthogonal part of each whitened column and take one matrix product with [r, E].
    """
    n_g = len(ks)
    obs = np.full(n_g, np.nan)
    sims = np.full((n_g, wm.E.shape[1]), np.nan)
    starts = np.concatenate([[0], np.cumsum(ks)[:-1]]).astype(int)
    one = [g for g in range(n_g) if ks[g] == 1]
    for a in range(0, len(one), GRID_CHUNK):  # a chunk at a time: a few copies of it live
        part = one[a:a + GRID_CHUNK]
        Z = Zw[:, starts[part]]
        Zp = Z - wm.Qx @ (wm.Qx.T @ Z)
        nz, nzp = np.linalg.norm(Z, axis=0), np.linalg.norm(Zp, axis=0)
        ok = (nz > 0) & (nzp > tol * np.maximum(nz, 1e-300))
        U = Zp[:, ok] / nzp[ok]
        idx = np.asarray(part)[ok]
        obs[idx] = (U.T @ wm.r) ** 2 / wm.s2
        sims[idx] = (U.T @ wm.E) ** 2 / wm.e_s2
    for g in range(n_g):
        if ks[g] == 1:
            continue
        Q = _basis(Zw[:, starts[g]:starts[g] + ks[g]], wm.Qx, tol)
        if Q is not None:
            obs[g] = np.sum((Q.T @ wm.r) ** 2) / wm.s2
            sims[g] = np.sum((Q.T @ wm.E) ** 2, axis=0) / wm.e_s2
    return obs, sims


def screen_linear(wm: Whitened, cand: Candidate, Z: list[np.ndarray],
                  Zw: np.ndarray) -> Screened | None:
    """Grid statistics of a linear candidate (whitened columns ``Zw``) and of the null sims."""
    ks = [z.shape[1] for z in Z]
    obs, sims = _grid_stats(wm, Zw, ks)
    keep = np.flatnonzero(np.isfinite(obs))
    if keep.size == 0:
        return None
    kk = np.asarray(ks)[keep]
    lp_obs = np.array([float(_log_sf(np.array(obs[g]), k)) for g, k in zip(keep, kk)])
    lp_sim = np.stack([_log_sf(sims[g], k) for g, k in zip(keep, kk)])  # (G, B)
    b = int(np.argmin(lp_obs))
    m = _m_eff(lp_sim.min(axis=0), keep.size)
    term = cand.grid[keep[b]]
    return Screened(cand, term, _searched_value(term), float(obs[keep[b]]), int(kk[b]),
                    float(lp_obs[b]), m, calibrated_log_p(float(lp_obs[b]), m))


def _searched_value(term: Term) -> float | None:
    for key in ("tau", "time", "r0", "width", "frequency"):
        if key in term.params:
            return float(term.params[key])
    return None


def frequency_grid(ctx: Context, min_cycles: float = 2.5) -> tuple[np.ndarray, int]:
    """Frequencies (Hz) of the zero-padded (x2) FFT between min_cycles/T and the block Nyquist."""
    nfft = 2 * ctx.grid.n
    f = np.fft.rfftfreq(nfft, d=ctx.grid.dt)
    sel = (f >= min_cycles / ctx.cov.duration) & (f <= 0.49 / ctx.grid.dt)
    return f, sel


def _periodogram(ctx: Context, R: np.ndarray, s2) -> np.ndarray:
    """2 |DFT|^2 / (n s2) of whitened residual columns R (n_obs, c) on the block grid."""
    full = np.zeros((ctx.grid.n, R.shape[1]))
    full[ctx.grid.mask > 0] = R
    F = np.fft.rfft(full, n=2 * ctx.grid.n, axis=0)
    return 2.0 * np.abs(F) ** 2 / (R.shape[0] * np.asarray(s2))


def screen_periodic(ctx: Context, wm: Whitened, cand: Candidate) -> Screened | None:
    f, sel = frequency_grid(ctx)
    if sel.sum() < 3:
        return None
    P = _periodogram(ctx, wm.r[:, None], wm.s2)[sel, 0]
    Ps = _periodogram(ctx, wm.E, wm.e_s2)[sel]
    b = int(np.argmax(P))
    lp = -0.5 * float(P[b])
    m = _m_eff(-0.5 * Ps.max(axis=0), int(sel.sum()))
    freq = float(f[sel][b])
    term = Term(Periodic.name, {"effect": cand.effect, "frequency": freq})
    return Screened(cand, term, freq, float(P[b]), 2, lp, m, calibrated_log_p(lp, m))


def fw_log_p(log_p: float, n_candidates: int) -> float:
    """Sidak family-wise log p over ``n_candidates``."""
    return calibrated_log_p(log_p, max(n_candidates, 1))


def screen(ctx: Context, fit: ModelFit, cands: list[Candidate], *, n_sims: int = 300,
           seed: int = 0) -> tuple[Whitened, list[Screened]]:
    """Screen every linear and spectral candidate against the fitted model (one filter pass).

    Returns the whitened model and the screened candidates, best (smallest calibrated p) first.
    Gauss-Markov noise components are chosen apart, by :mod:`fogbayes.loop.noise_model`.
    """
    lin = [c for c in cands if c.kind == "linear"]
    Zs = [candidate_columns(ctx, c) for c in lin]
    flat = [z for zs in Zs for z in zs]
    wm, Zw = whitened_model(ctx, fit, n_sims=n_sims, seed=seed, extra=flat or None)
    del flat  # the block columns are whitened: only their widths are needed below
    Zs = [[np.empty((0, z.shape[1])) for z in zs] for zs in Zs]
    out, j = [], 0
    for c, zs in zip(lin, Zs):
        k = sum(z.shape[1] for z in zs)
        s = screen_linear(wm, c, zs, Zw[:, j:j + k])
        j += k
        if s is not None:
            out.append(s)
    for c in cands:
        if c.kind == "spectral":
            s = screen_periodic(ctx, wm, c)
            if s is not None:
                out.append(s)
    out.sort(key=lambda s: s.log_p)
    return wm, out
