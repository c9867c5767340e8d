"""Model-free scans of the final residual for structure no candidate names (``unexplained``).

Each is calibrated by simulation under the fitted noise, p = (1 + #{sims >= obs}) / (1 + n_sims),
reported below alpha / (scans of its kind): ``covariate`` (Legendre P_1..P_6 of each covariate,
LR ~ chi^2_k), ``spectral_line`` (whitened periodogram; above block Nyquist R_k = P_k ln2 / med_k),
``change_point`` (CUSUM of r and r^2), ``autocorrelation`` (Ljung-Box, lags 1..20),
``noise_model_at_bound`` (a slow variance at its upper bound,
:data:`fogbayes.inference.noise_ssm.LOG_BOUNDS` or :mod:`fogbayes.loop.noise_prior`'s cap).
"""

from __future__ import annotations

import math

import numpy as np

from ..support.tails import chi2_sf
from ..inference import noise_ssm as ns
from ..inference import noise_fit as nfit
from . import nullsim
from .context import Context
from .evidence import _periodogram, frequency_grid, whiten_columns
from .fitting import ModelFit
from .reml import with_reml

N_BINS = 10


def _p(obs: float, sims: np.ndarray) -> float:
    return float((1 + np.sum(sims >= obs)) / (1 + sims.size))


def _sim_residuals(ctx: Context, fit: ModelFit, n_sims: int, seed: int,
                   cache: dict | None = None):
    """Block residual of the data and of simulated noise after the same GLS fit (raw and whitened)."""
    nf = with_reml(ctx, fit, cache).noise  # REML: ML leaves too little slow noise in the nulls
    sims = nullsim.simulate(nf.spec, nf.theta, nf.sigma2, ctx.grid.w, n_sims, seed=seed)
    obs = ctx.grid.mask > 0
    p = fit.X.shape[1]
    Y = np.column_stack([np.where(obs, ctx.y, 0.0), sims])
    W = whiten_columns(ctx, nf.spec, nf.theta, np.column_stack([Y, fit.X]))
    Xw = W[:, -p:]
    B, *_ = np.linalg.lstsq(Xw, W[:, :-p], rcond=None)
    raw = Y[obs] - fit.X[obs] @ B            # (n_obs, 1 + n_sims)
    white = W[:, :-p] - Xw @ B
    return raw, white


def _covariates(ctx: Context) -> dict[str, np.ndarray]:
    c, out = ctx.bcov, {"time": ctx.bcov.t}
    dt = ctx.grid.dt
    for j, name in enumerate(c.names):
        if np.ptp(c.T[:, j]) > 0.1:
            out[name] = c.T[:, j]
            out[f"d({name})/dt"] = np.gradient(c.T[:, j], dt) * 60.0
        if j > 0 and np.ptp(c.T[:, j] - c.T[:, 0]) > 0.05:
            out[f"{name} - {c.names[0]}"] = c.T[:, j] - c.T[:, 0]
    if c.omega is not None and np.ptp(c.omega) > 0:
        out["input_rate"] = c.omega
        out["|input_rate|"] = np.abs(c.omega)
    return out


def _smooth_basis(x: np.ndarray, X: np.ndarray, obs: np.ndarray, degree: int = 6) -> np.ndarray:
    """Legendre P_1..P_degree of the scaled covariate, minus columns the design already spans."""
    lo, hi = float(np.min(x[obs])), float(np.max(x[obs]))
    z = (2.0 * x - lo - hi) / max(hi - lo, 1e-300)
    P = np.polynomial.legendre.legvander(np.clip(z, -1, 1), degree)[:, 1:]
    keep, basis = [], X[obs]
    for j in range(P.shape[1]):
        c = P[obs, j]
        coef, *_ = np.linalg.lstsq(basis, c, rcond=None)
        if np.linalg.norm(c - basis @ coef) > 1e-3 * np.linalg.norm(c):
            keep.append(j)
            basis = np.column_stack([basis, c])
    return P[:, keep]


def covariate_scans(ctx: Context, fit: ModelFit, alpha: float) -> list[dict]:
    """Residual against each covariate: GLS likelihood-ratio test of a smooth function of it.

    The model is refitted with Legendre polynomials P_1..P_6 of the scaled covariate added
    (noise hyperparameters re-estimated, so slow structure the current noise model has
    absorbed cannot hide in a widened null band); 2 dlogL ~ chi^2_k under "the residual
    does not depend on it". Reported: the fitted function at 10 quantile points with its
    GLS standard error.
    """
    obs = ctx.grid.mask > 0
    covs = _covariates(ctx)
    found = []
    spec = fit.noise.spec
    for name, x in covs.items():
        D = _smooth_basis(x, fit.X, obs)
        if D.shape[1] == 0:
            continue
        X1 = np.column_stack([fit.X, D])
        k = D.shape[1]
        fixed = ns.gls(spec, fit.noise.theta, ctx.y, X1, ctx.grid.mask, ctx.grid.w).loglik
        if chi2_sf(2.0 * (fixed - fit.loglik), k) >= 0.1 / len(covs):
            continue  # not even suggestive at the current noise model (as the loop's gate)
        alt = nfit.fit_noise(spec, ctx.y, X1, ctx.grid.mask, ctx.grid.w,
                           extra_starts=fit.noise.theta[None] if fit.noise.theta.size else None)
        lr = max(2.0 * (alt.loglik - fit.loglik), 0.0)
        p = float(chi2_sf(lr, k))
        if p < alpha / max(len(covs), 1):
            q = np.quantile(x[obs], np.linspace(0.05, 0.95, N_BINS))
            rows = np.array([np.argmin(np.abs(x - v)) for v in q])
            f = D[rows] @ alt.beta[-k:]
            C = alt.cov_beta[-k:, -k:]
            se = np.sqrt(np.einsum("ij,jk,ik->i", D[rows], C, D[rows]))
            found.append({"kind": "covariate", "detail": {
                "covariate": name, "p_value": p, "likelihood_ratio": lr, "dof": k,
                "at": q, "residual_function_deg_h": f - f.mean(),
                "stderr_deg_h": se,
                "note": "the residual depends on this covariate (smooth GLS fit under the "
                        "re-estimated noise model)"}})
    return found


def spectral_scans(ctx: Context, fit: ModelFit, white: np.ndarray, alpha: float) -> list[dict]:
    found = []
    f, sel = frequency_grid(ctx)
    if sel.sum() >= 3:
        s2 = np.sum(white ** 2, axis=0) / white.shape[0]
        P = _periodogram(ctx, white, s2)[sel]
        b = int(np.argmax(P[:, 0]))
        p = _p(P[b, 0], P.max(axis=0)[1:])
        if p < alpha:
            found.append({"kind": "spectral_line", "detail": {
                "frequency_hz": float(f[sel][b]), "false_alarm_probability": p,
                "band": "block level"}})
    found += _fast_lines(ctx, fit, alpha)
    return found


def _fast_lines(ctx: Context, fit: ModelFit, alpha: float) -> list[dict]:
    """Lines above the block Nyquist frequency in the per-sample residual (uniform runs only)."""
    if ctx.grid.count.max() < 4:
        return []
    t = ctx.cov.t
    dt = float(np.median(np.diff(t)))
    if np.max(np.diff(t)) > 1.5 * dt:
        return []  # gaps: a plain FFT would see the gap pattern, not the gyro
    r = np.where(ctx.outlier, 0.0, fit.residual)
    r = (r - r.mean()) * np.hanning(r.size)  # Hann: slow drifts must not leak upwards
    P = np.abs(np.fft.rfft(r)) ** 2
    f = np.fft.rfftfreq(r.size, d=dt)
    sel = (f > 1.0 / ctx.grid.dt) & (f < 0.95 * f[-1])  # the Nyquist edge leaks (Hann)
    if sel.sum() < 200:
        return []
    Ps = P[sel]
    from scipy.ndimage import median_filter  # on use (0.1 s): a 1 Hz record never gets here

    bg = median_filter(Ps, size=101, mode="nearest") / math.log(2.0)
    R = Ps / np.maximum(bg, 1e-300)
    k = int(np.argmax(R))
    fap = -math.expm1(Ps.size * math.log1p(-min(math.exp(-R[k]), 1 - 1e-16)))
    if fap < alpha:
        return [{"kind": "spectral_line", "detail": {
            "frequency_hz": float(f[sel][k]), "false_alarm_probability": fap,
            "band": "above the block Nyquist frequency (per-sample residual)",
            "power_ratio": float(R[k])}}]
    return []


def _cusum(x: np.ndarray) -> np.ndarray:
    x = x - x.mean(axis=0)
    s = np.cumsum(x, axis=0) / (np.sqrt(x.shape[0]) * (x.std(axis=0) + 1e-300))
    return np.abs(s).max(axis=0), np.abs(s).argmax(axis=0)


def change_point_scans(ctx: Context, white: np.ndarray, alpha: float) -> list[dict]:
    found = []
    tb = ctx.grid.t[ctx.grid.mask > 0]
    for what, x in (("mean", white), ("variance", white ** 2)):
        stat, where = _cusum(x)
        p = _p(stat[0], stat[1:])
        if p < alpha / 2:
            found.append({"kind": "change_point", "detail": {
                "in": what, "time_s": float(tb[where[0]]), "p_value": p}})
    return found


def autocorrelation_scan(white: np.ndarray, alpha: float, lags: int = 20) -> list[dict]:
    x = white - white.mean(axis=0)
    n = x.shape[0]
    d = np.sum(x * x, axis=0)
    rho = np.stack([np.sum(x[k:] * x[:-k], axis=0) / d for k in range(1, lags + 1)])
    q = n * (n + 2) * np.sum(rho ** 2 / (n - np.arange(1, lags + 1))[:, None], axis=0)
    p = _p(q[0], q[1:])
    if p < alpha:
        return [{"kind": "autocorrelation", "detail": {
            "ljung_box_q": float(q[0]), "lags": lags, "p_value": p,
            "acf": rho[:, 0], "note": "the whitened residual is not white: the noise model "
                                      "misses correlation"}}]
    return []


def noise_bound_scan(fit: ModelFit, tol: float = 1e-2) -> list[dict]:
    """Noise variances at the upper end of their range (module doc)."""
    spec = fit.noise.spec
    p = ns.unpack(spec, fit.noise.theta)
    parts = ([("flicker", float(p.log_flicker))] if spec.bank_taus else []) + \
        ([("rw", float(p.log_rw))] if spec.random_walk else [])
    out = []
    for name, value in parts:
        hi = spec.log_rw_max if name == "rw" else ns.LOG_BOUNDS[name][1]
        if value >= hi - tol:
            capped = name == "rw" and hi < ns.LOG_BOUNDS["rw"][1]
            note = ("the random walk sits at the cap of the noise prior: the record wanders "
                    "more than the static run allows, so it holds an effect no candidate "
                    "names, or the prior does not fit this record (another sensor or "
                    "environment); read the other scans" if capped else
                    "the fitted noise takes up as much slow structure as it can: the "
                    "residual holds an effect no candidate names and the evidence of "
                    "each step is unreliable; declare more of the model (--orders) or "
                    "read the other scans")
            out.append({"kind": "noise_model_at_bound", "detail": {
                "component": {"rw": "random_walk", "flicker": "flicker"}[name],
                "log_variance_ratio": value, "upper_bound": hi,
                "bound": "noise prior" if capped else "search range", "note": note}})
    return out


def scan_unexplained(ctx: Context, fit: ModelFit, *, seed: int = 0, alpha: float = 0.01,
                     n_sims: int = 200, cache: dict | None = None) -> list[dict]:
    """All scans of the final residual; returns the ``unexplained`` entries (``cache``: the
    REML noise of ``fit``, :func:`fogbayes.loop.reml.with_reml`)."""
    _, white = _sim_residuals(ctx, fit, n_sims, seed + 31, cache)
    return (noise_bound_scan(fit) + covariate_scans(ctx, fit, alpha)
            + spectral_scans(ctx, fit, white, alpha) + change_point_scans(ctx, white, alpha)
            + autocorrelation_scan(white, alpha))
