"""The loop's noise model, chosen apart from the deterministic effects.

White + flicker bank + random walk always; Gauss-Markov components are added while
LR = 2 [logL(M + 1) - logL(M)] has p = P(chi^2_2 > LR) < alpha (:mod:`fogbayes.loop.markov`)
and dropped when no longer passing; re-chosen after each accepted effect.
:func:`best_with_fewer` lets a candidate's refit replace a component. Reported as the noise
model, never as a step.
"""

from __future__ import annotations

import math

import numpy as np

from .context import Context
from .fitting import ModelFit
from .markov import markov_log_p, markov_start, refit_markov
from ..effects.terms import design
from ..inference import noise_ssm as ns
from ..inference import noise_fit as nfit

#: most Gauss-Markov components the loop considers (beyond white, flicker and walk)
MAX_COMPONENTS = 2


def _without(spec: ns.NoiseSpec, theta, j: int) -> tuple[ns.NoiseSpec, np.ndarray]:
    """(spec, theta) with Gauss-Markov component ``j`` removed."""
    p = ns.unpack(spec, theta)
    keep = [i for i in range(spec.n_markov) if i != j]
    red = spec._replace(n_markov=spec.n_markov - 1)
    keep = np.asarray(keep, int)
    q = ns.NoiseParams(p.log_flicker, p.log_rw, np.asarray(p.markov_logvar)[keep],
                       np.asarray(p.markov_logtau)[keep])
    return red, np.asarray(ns.pack(red, q), float)


def best_with_fewer(ctx: Context, fit: ModelFit) -> ModelFit | None:
    """The best refit of ``fit``'s terms with one Gauss-Markov component fewer (None if none)."""
    spec = fit.noise.spec
    best = None
    for j in range(spec.n_markov):
        red, start = _without(spec, fit.noise.theta, j)
        nf = nfit.fit_noise(red, ctx.y, fit.X, ctx.grid.mask, ctx.grid.w,
                          extra_starts=start[None] if start.size else None)
        if best is None or nf.loglik > best.loglik:
            best = nf
    if best is None:
        return None
    res = ctx.rate - design(list(fit.terms), ctx.cov) @ best.beta
    return ModelFit(fit.terms, fit.X, best, res)


def components(fit: ModelFit) -> list[dict]:
    """Each Gauss-Markov component: stationary std (deg/h, per sample) and tau_c (s)."""
    nf = fit.noise
    p = ns.unpack(nf.spec, nf.theta)
    out = []
    for lv, lt in zip(np.asarray(p.markov_logvar), np.asarray(p.markov_logtau)):
        tau_c = float(np.exp(lt))
        x = nf.spec.dt / tau_c  # block averaging keeps 2 (x - 1 + e^-x) / x^2 of the variance
        keep = 2.0 * (x - 1.0 + np.exp(-x)) / x ** 2
        out.append({"term": "gauss_markov_noise", "tau_c_s": tau_c,
                    "sigma_deg_h": float(np.sqrt(nf.sigma2 * np.exp(lv) / keep))})
    return out


def _row(action: str, after: str, lr: float, lp: float, fit: ModelFit) -> dict:
    return {"action": action, "after": after, "likelihood_ratio": lr,
            "log10_p": lp / math.log(10), "null": "chi^2_2",
            "components": components(fit)}


def choose(ctx: Context, fit: ModelFit, *, alpha: float, after: str = "base model",
           max_components: int = MAX_COMPONENTS) -> tuple[ModelFit, list[dict]]:
    """Re-choose the Gauss-Markov components of ``fit`` (module doc); (fit, evidence rows).

    ``after`` names the model the choice was made for (for the evidence rows).
    """
    rows: list[dict] = []
    while fit.noise.spec.n_markov > 0:
        red = best_with_fewer(ctx, fit)
        lr = max(2.0 * (fit.loglik - red.loglik), 0.0)
        lp = markov_log_p(lr)
        if lp < math.log(alpha):
            break
        rows.append(_row("dropped", after, lr, lp, red))
        fit = red
    while fit.noise.spec.n_markov < max_components:
        s = markov_start(ctx, fit)
        if s is None:
            break
        try:
            alt = refit_markov(ctx, fit, s)
        except (np.linalg.LinAlgError, FloatingPointError, ValueError):
            break
        lr = max(2.0 * (alt.loglik - fit.loglik), 0.0)
        lp = markov_log_p(lr)
        ok = lp < math.log(alpha)
        rows.append(_row("added" if ok else "not added", after, lr, lp, alt))
        if not ok:
            break
        fit = alt
    return fit, rows


def sentence(fit: ModelFit, rows=()) -> str:
    """The noise model in words (white, flicker, walk, Gauss-Markov components) and how it
    was chosen; ``rows``: the evidence rows of :func:`choose`."""
    nf = fit.noise
    parts = ["white"] + (["flicker"] if nf.spec.bank_taus else []) + (
        ["random walk"] if nf.spec.random_walk else [])
    parts += [f"Gauss-Markov (sigma {c['sigma_deg_h']:.3g} deg/h, tau_c {c['tau_c_s']:.3g} s)"
              for c in components(fit)]
    n_tried = sum(r["action"] != "dropped" for r in rows)
    return (f"noise model: {' + '.join(parts)}; chosen apart from the effects, before the "
            f"search and after each added effect ({n_tried} Gauss-Markov component(s) weighed "
            f"by chi^2_2 likelihood ratios), never counted as a step.")
