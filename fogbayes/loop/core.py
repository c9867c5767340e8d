"""The closed loop: fit -> diagnose -> weigh the shortlisted candidates -> add -> refit.

Fit the base model (GLS, noise by ML), choose Gauss-Markov components (:mod:`.noise_model`);
then up to ``max_steps`` times: screen candidates, refit the ``n_refit`` best, keep those with
p_familywise < alpha, screening p < 0.1 and d elpd_loo > 0, rank them (:mod:`.ranking`), add the
winner (polished, :func:`fogbayes.loop.refine.polish`) if held-out folds agree
(:mod:`.holdout`), re-choose the noise; finally scan for ``unexplained`` structure.
Statistics: :mod:`fogbayes.loop.evidence`; rule: :data:`RULE`.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from . import elpd as el
from .bartlett import bartlett_factor, in_walk_mode, leaves_walk_mode
from . import evidence as ev
from .candidates import candidates_for
from ..effects import REGISTRY
from ..effects.simulator_only import MarkovNoise
from .context import Context, make_context
from .fitting import ModelFit, fit_terms
from .noise_prior import NoisePrior
from .refine import polish, refine
from .reml import with_reml
from .scans import scan_unexplained
from ..support.lazy import host_device
from ..inference import noise_fit as nfit
from ..thermal.workflow import DEFAULT_ORDERS
from ._threads import single_thread_blas
from .adev_misfit import adev_misfit
from .bases import ALLOWED, allowed as allowed_for, base_terms
from .calibration import calibration_json, input_json
from .estimator import publish, reml_noise
from .declared import check_declared, declare, evidence_json as declared_evidence
from .separable import detectability, separability_warnings
from .identifiable import collinearity_warnings
from .compensate import compensate
from .describe import describe
from .metrics import Metrics, block_rms, stability
from . import holdout
from .progress import tell
from .noise_model import best_with_fewer, choose as choose_noise, components
from .ranking import alternatives, duel_json, rank_supported, supported_trials
from .result import LoopResult, Rejected, Step

RULE = ("a candidate is supported if (1) its likelihood ratio 2(logL_with - logL_without), "
        "both models refitted by GLS with white + flicker + random-walk noise hyperparameters by "
        "maximum likelihood on block means (Kalman filter), has a family-wise p-value "
        "(Sidak over the candidates) below alpha, the p-value of a searched parameter "
        "(time, frequency, tau, ...) being calibrated by a parametric bootstrap of the "
        "minimum p over its grid under the current model's noise (REML hyperparameters: ML "
        "ones leave too little slow noise in the null series); and (2) its PSIS-LOO elpd "
        "(one-step-ahead predictive densities of the block means) exceeds the model "
        "without it; a linear candidate must also reach family-wise p < 0.1 in the "
        "fixed-noise screening under the fitted noise model (the refitted ratio also gains "
        "from re-estimating the noise; a second screening without a random walk, made when "
        "the fit is in the walk mode, shortlists candidates, and gates one only if its refit "
        "drops the walk, in which case its ratio is divided by a bootstrap Bartlett factor "
        "(mean refitted ratio / dof over series simulated from the current fit, 20 at a time "
        "until the decision is the same at +-2 standard errors, at most 100), the walk "
        "variance piling up at zero when a slow term is offered); "
        "a candidate's refit may also drop one of the model's Gauss-Markov noise components "
        "(the noise model is chosen apart from the effects, before the search and after each "
        "added effect, by refitted ratios against chi^2_2). Supported candidates are ranked "
        "by the calibrated p-value of the refit, then the best meets every other supported "
        "linear candidate in a duel: D = 2 logL(other) - 2 logL(best) at the REML noise of "
        "the model with both, each at the best value of "
        "its own (refined) grid, with a parametric-bootstrap p-value under each hypothesis "
        "(level 0.05); the "
        "one not rejected wins; if neither is rejected they are indistinguishable, the one "
        "with fewer searched parameters is kept and the other listed in 'alternatives'; "
        "if both are, the one whose model predicts held-out folds better (below). The "
        "winner is kept only if the model with it "
        "predicts held-out time-blocked folds (10, each scored by its exact predictive "
        "density given the other blocks, coefficients refitted without it, a step's time "
        "averaged over every block boundary with the weights the other blocks give each "
        "time; folds that "
        "cannot identify its coefficients left out) at least as well as the model without "
        "it; otherwise it is set aside and the next step decides among the others. "
        "alpha = 0.01 by default. After the decision, "
        "an accepted step's time is placed to 1/20 of a block (exact block columns, kept "
        "if the refitted likelihood rises).")


class Options(NamedTuple):
    max_steps: int = 5
    alpha: float = ev.ALPHA
    n_sims: int = 300
    n_refit: int = 3
    seed: int = 0
    effects: tuple[str, ...] | None = None
    target_blocks: int = 2500


def _published(ctx: Context, fit: ModelFit, cache: dict) -> ModelFit:
    """:func:`.estimator.publish` of ``fit``, its covariance under REML noise, once per fit."""
    key = ("published", np.asarray(fit.beta).tobytes(), np.asarray(fit.noise.theta).tobytes())
    if key not in cache:
        cache[key] = publish(ctx, fit, cov_noise=reml_noise(ctx, fit, cache))
    return cache[key]


def _metrics(ctx: Context, fit: ModelFit, seed: int, cache: dict) -> Metrics:
    """Metrics of the model as a calibration: the residual of its published coefficients
    (:mod:`.estimator`: IEEE 952 constant), so the RMS is the compensated output's."""
    e = el.elpd(ctx, fit, seed=seed, cache=cache)
    t = ctx.cov.t
    r = _published(ctx, fit, cache).residual
    return Metrics(block_rms(t, r, ctx.outlier), stability(t, r, ctx.outlier), e.elpd_loo, e.se)


class Trial(NamedTuple):
    screened: ev.Screened
    fit: ModelFit
    lr: float
    log_p: float
    log_p_fw: float
    bartlett: float = 1.0  # scale of the ratio's null (> 1 where the refit dropped the walk)


def _trial(ctx: Context, fit: ModelFit, wm: ev.Whitened, s: ev.Screened, n_cand: int, *,
           alpha: float = ev.ALPHA, seed: int = 0) -> Trial:
    """Refit the model with candidate ``s`` added; its calibrated likelihood-ratio p-value.

    Where the refit drops the random walk of the current fit, the ratio is divided by its
    bootstrap Bartlett factor (:mod:`fogbayes.loop.bartlett`; measured only when the
    ratio would pass ``alpha`` without it), and the screening without a walk becomes the
    candidate's gate (``gate_log_p`` cleared): the refit itself chose that noise model.
    """
    c = 1.0
    term, _ = refine(ctx, wm, s)
    alt = fit_terms(ctx, fit.terms + (term,), spec=fit.noise.spec, theta0=fit.noise.theta)
    fewer = best_with_fewer(ctx, alt)  # the candidate may stand for a noise component
    if fewer is not None and fewer.loglik > alt.loglik:
        alt = fewer
    lr = max(2.0 * (alt.loglik - fit.loglik), 0.0)
    lp = ev.calibrated_log_p(ev.log_chi2_sf(lr, s.dof), s.m_eff)
    if leaves_walk_mode(fit, alt):
        if ev.fw_log_p(lp, n_cand) < math.log(alpha):
            def log_p(c: float) -> float:
                return ev.calibrated_log_p(ev.log_chi2_sf(lr / c, s.dof), s.m_eff)

            def passes(c: float) -> bool:
                return ev.fw_log_p(log_p(c), n_cand) < math.log(alpha)

            c = bartlett_factor(ctx, fit, alt, s.dof, seed=seed, decide=passes)
            lp = log_p(c)
        s = s._replace(gate_log_p=None)
    return Trial(s, alt, lr, lp, ev.fw_log_p(lp, n_cand), c)


def _safe_trial(ctx, fit, wm, s, n_cand, **kw) -> Trial | None:
    """A refit that fails numerically (e.g. a column collinear with the model) is no evidence."""
    try:
        tr = _trial(ctx, fit, wm, s, n_cand, **kw)
    except (np.linalg.LinAlgError, FloatingPointError, ValueError):
        return None
    return tr if math.isfinite(tr.log_p) else None


def _ranking(screened: list[ev.Screened], n_cand: int) -> list[dict]:
    return [{"effect": s.candidate.effect, "screen_lr": s.stat, "dof": s.dof,
             "m_eff": s.m_eff, "log10_p": s.log_p / math.log(10),
             "log10_p_familywise": ev.fw_log_p(s.log_p, n_cand) / math.log(10),
             "searched_value": s.best_value} for s in screened]


def _evidence(tr: Trial, d: el.ElpdDiff | None, opts: Options, n_cand: int, trials, ranking):
    return {"rule": RULE, "alpha": opts.alpha, "n_candidates": n_cand,
            "likelihood_ratio": tr.lr, "bartlett_factor": tr.bartlett,
            "dof": tr.screened.dof, "m_eff": tr.screened.m_eff,
            "noise_components": len(components(tr.fit)),
            "log10_p": tr.log_p / math.log(10),
            "log10_p_familywise": tr.log_p_fw / math.log(10),
            "elpd_diff": None if d is None else d.diff, "elpd_diff_se": None if d is None else d.se,
            "elpd_with": None if d is None else d.elpd_with,
            "elpd_without": None if d is None else d.elpd_without,
            "elpd_criterion": None if d is None else d.ic,
            "n_sims": opts.n_sims,
            "refitted": [{"effect": t.screened.candidate.effect, "likelihood_ratio": t.lr,
                          "bartlett_factor": t.bartlett, "log10_p": t.log_p / math.log(10)}
                         for t in trials],
            "screening": ranking}


def _two_looks(log_p: float) -> float:
    """Bonferroni log p of the better of two looks: log min(1, 2 p) (a p-value is at most 1)."""
    return min(0.0, log_p + math.log(2.0))


def _screen_all(ctx: Context, fit: ModelFit, cands, opts: Options, step: int,
                cache: dict | None = None):
    """Screened candidates, each with the whitened model it was screened against.

    The noise likelihood is often bimodal: a random walk can take up a step or a warm-up
    that a flicker-dominated noise model would leave in the residual. When the current
    fit sits in the random-walk mode, every candidate is also screened against the best
    noise model without a random walk, keeping the smaller p (with a factor 2 for the
    two looks), so the shortlist does not lose an effect the walk has swallowed. That
    second look is not calibrated when the record's noise really has a walk (any slow
    term then looks significant: family-wise p down to 1e-15 on clean records), so the
    screening gate of :func:`fogbayes.loop.ranking.supported_trials` reads the first
    look's p (``Screened.gate_log_p``), the one under the noise model the data chose --
    unless the candidate's own refit drops the walk (:func:`_trial`).

    The screening whitens and simulates under the REML noise hyperparameters of the
    current design (:mod:`fogbayes.loop.reml`): ML ones leave too little slow noise
    in the null series and make slow candidates look significant too often.
    """
    seed = opts.seed + 7919 * step
    wm, screened = ev.screen(ctx, with_reml(ctx, fit, cache), cands, n_sims=opts.n_sims,
                             seed=seed)
    pairs = {s.candidate.effect: (s, wm) for s in screened}
    spec = fit.noise.spec
    if in_walk_mode(fit):
        alt_spec = spec._replace(random_walk=False)
        nf = nfit.fit_noise(alt_spec, ctx.y, fit.X, ctx.grid.mask, ctx.grid.w)
        wm2, screened2 = ev.screen(ctx, with_reml(ctx, fit._replace(noise=nf), cache), cands,
                                   n_sims=opts.n_sims, seed=seed + 1)
        for s2 in screened2:
            have = pairs.get(s2.candidate.effect)
            gate = 0.0 if have is None else have[0].log_p  # not screenable under the fit: p 1
            if have is None or s2.log_p < have[0].log_p:
                pairs[s2.candidate.effect] = (s2._replace(log_p=_two_looks(s2.log_p),
                                                          gate_log_p=gate), wm2)
            else:
                pairs[s2.candidate.effect] = (have[0]._replace(
                    log_p=_two_looks(have[0].log_p), gate_log_p=gate), have[1])
    return sorted(pairs.values(), key=lambda p: p[0].log_p)


def _decide(ctx: Context, fit: ModelFit, opts: Options, step: int, cache: dict):
    """Screen, refit the shortlist, apply the rule. Returns (accepted Trial | None, evidence)."""
    cands = candidates_for(ctx, fit.terms, effects=opts.effects)
    if not cands:
        return None, None, {"reason": "no candidate left"}
    tell(step + 1, opts.max_steps, f"screening {len(cands)} candidates")
    pairs = _screen_all(ctx, fit, cands, opts, step, cache)
    screened = [p[0] for p in pairs]
    n_cand = len(screened)
    if n_cand == 0:
        return None, None, {"reason": "no identifiable candidate"}
    ranking = _ranking(screened, n_cand)
    short = pairs[:opts.n_refit]

    def trial(i, s, wm):
        tell(step + 1, opts.max_steps, f"refitting {s.candidate.effect}",
             s.candidate.effect, i + 1, len(short))
        return _safe_trial(ctx, fit, wm, s, n_cand, alpha=opts.alpha,
                           seed=opts.seed + 7919 * step + 17)

    trials = sorted((t for t in (trial(i, s, wm) for i, (s, wm) in enumerate(short))
                     if t is not None), key=lambda t: t.log_p)
    tell(step + 1, opts.max_steps, "weighing the evidence")
    supported = supported_trials(ctx, fit, trials, opts, n_cand, cache)
    if not supported:
        best = trials[0] if trials else None
        evid = None if best is None else _evidence(best, None, opts, n_cand, trials, ranking)
        return None, None, {"reason": "no candidate supported by the evidence", "best": evid}
    (tr, d), duels = rank_supported(ctx, fit, supported, opts, step, cache)
    evid = _evidence(tr, d, opts, n_cand, trials, ranking)
    evid["alternatives"] = alternatives(ctx, tr, duels, opts, cache)
    evid["duels"] = [duel_json(a, b, du) for a, b, du in duels]
    return tr, evid, None


def run_loop(rec, model: str = "bias-t", *, orders: str | None = None, max_steps: int = 5,
             alpha: float = ev.ALPHA, seed: int = 0, n_sims: int = 300, n_refit: int = 3,
             effects: tuple[str, ...] | None = None, target_blocks: int = 2500,
             noise_prior: NoisePrior | None = None, declared=()) -> LoopResult:
    """Run the closed loop on a :class:`~fogbayes.data.Recording` from base ``model``.

    Args:
        rec: the recording; model: ``bias-t``, ``thermal``, ``composite`` or ``allan``.
        orders: base-model orders (see :func:`fogbayes.loop.bases.parse_orders`).
        max_steps: add at most this many effects; alpha: family-wise level of each step.
        seed: seed of the bootstrap calibration and the ELPD draws; n_sims: simulated null
            series per step; n_refit: candidates refitted per step.
        effects: restrict the candidate names (``markov_noise`` in them, as by default:
            choose Gauss-Markov noise components, :mod:`.noise_model`); target_blocks:
            block-grid size.
        noise_prior: a cap on the random walk from a static run
            (:mod:`fogbayes.loop.noise_prior`), applied to every fit of the loop.
        declared: effect names added to the base model, in order, before the search: each a
            step with evidence ``declared`` and no test (:mod:`.declared`); ``max_steps=0``
            with them is the base model plus the declared effects.
    """
    declared = check_declared(declared, model, where="declared")
    with single_thread_blas(), host_device():  # sequential scans: the CPU beats a GPU
        return _run(rec, model, orders, max_steps, alpha, seed, n_sims, n_refit, effects,
                    target_blocks, noise_prior, declared)


def _run(rec, model, orders, max_steps, alpha, seed, n_sims, n_refit, effects,
         target_blocks, noise_prior, declared=()) -> LoopResult:
    allowed = tuple(e for e in allowed_for(model) if effects is None or e in effects) \
        if model in ALLOWED else effects
    opts = Options(max_steps, alpha, n_sims, n_refit, seed, allowed, target_blocks)
    tell(0, max_steps, f"fitting the {model} base")
    ctx = make_context(rec, target_blocks=target_blocks)
    base = base_terms(ctx, model, orders, source=rec.meta.source)
    fit = fit_terms(ctx, base)
    if noise_prior is not None:  # the cap is on the absolute walk: it needs the white level
        ctx = ctx._replace(spec=noise_prior.capped(ctx.spec, fit.noise.sigma2))
        fit = fit_terms(ctx, base)
    markov = allowed is None or MarkovNoise.name in allowed
    noise_rows: list[dict] = []
    if markov:
        tell(0, max_steps, "choosing the noise model")
        fit, noise_rows = choose_noise(ctx, fit, alpha=alpha)
    fit0 = fit
    cache: dict = {}
    m0 = _metrics(ctx, fit, seed, cache)
    cur, steps = m0, []
    stop = Rejected("max_steps reached", {})
    h_cur = holdout.score(ctx, fit)
    h_base, held_out = h_cur, []
    for i, name in enumerate(declared):
        tell(0, max_steps, f"adding the declared {name}", name)
        d = declare(ctx, fit, name, n_sims=n_sims, seed=seed + 7919 * (max_steps + i + 1),
                    cache=cache)
        new, rows = d.fit, []
        if markov:
            new, rows = choose_noise(ctx, new, alpha=alpha, after=f"+ {name}")
        noise_rows += rows
        m1 = _metrics(ctx, new, seed, cache)
        term = new.terms[-1]
        steps.append(Step(name, d.screened.candidate.covariates, term, _detail(new, term, rec),
                          declared_evidence(d), cur.rms, m1.rms, m1, new))
        fit, cur = new, m1
        h_cur = holdout.score(ctx, fit)
    for k in range(max_steps):
        tr, evid, why = _decide(ctx, fit, opts, k, cache)
        if tr is None:
            stop = Rejected(why["reason"], why.get("best") or {})
            break
        s = tr.screened
        tell(k + 1, max_steps, f"adding {s.candidate.effect}", s.candidate.effect)
        new = polish(ctx, fit, tr.fit)  # a step's time, or a searched scale, under the refit
        rows: list[dict] = []
        if markov:
            new, rows = choose_noise(ctx, new, alpha=alpha,
                                     after=f"+ {s.candidate.effect}")
        tell(k + 1, max_steps, f"held-out check of {s.candidate.effect}", s.candidate.effect)
        h_new = holdout.score(ctx, new, search=holdout.searched_columns(ctx, s.candidate, new))
        cmp = holdout.compare(h_new, h_cur)
        evid["holdout"] = holdout.to_json(cmp)
        if not cmp.kept:  # supported in-sample, worse out of it
            held_out.append({"effect": s.candidate.effect, **evid["holdout"]})
            opts = opts._replace(effects=tuple(
                e for e in (opts.effects or tuple(REGISTRY)) if e != s.candidate.effect))
            continue
        noise_rows += rows
        m1 = _metrics(ctx, new, seed, cache)
        term = new.terms[-1]
        detail = _detail(new, term, rec)
        steps.append(Step(s.candidate.effect, s.candidate.covariates, term, detail, evid,
                          cur.rms, m1.rms, m1, new))
        fit, cur = new, m1
        h_cur = holdout.score(ctx, fit)  # the next term is judged with this one held fixed
    tell(None, max_steps, "scanning the residual for unexplained structure")
    unexplained = scan_unexplained(ctx, fit, seed=seed, alpha=alpha, cache=cache)
    # what the final model could still be missing on this programme and noise
    detectable = tuple(detectability(ctx, fit, alpha, effects=opts.effects)) \
        if model != "allan" else ()
    noise_adev = None
    if model == "allan":
        story, noise_adev = _allan_story(rec, ctx, steps, fit)
        unexplained += story
    # coefficients under the noise model less its walk, the constant the run's time average
    # (IEEE 952), the covariance under the full model: :mod:`.estimator`
    fit, fit0 = _published(ctx, fit, cache), _published(ctx, fit0, cache)
    _read_published(steps, fit, rec)
    comp = compensate(rec, ctx, fit, model)
    held = {"folds": holdout.N_FOLDS, "lpd_base": h_base.lpd, "lpd_final": h_cur.lpd,
            "not_kept": held_out, **_plain_check(ctx, model, fit, h_cur)}
    warnings = tuple(collinearity_warnings(ctx)) + tuple(
        separability_warnings(list(detectable), cur.rms))
    if held.get("final_not_worse_than_plain_fit") is False:
        warnings += (f"the final model predicts held-out time blocks worse than "
                     f"{held['plain_fit']} (log predictive density {h_cur.lpd:.1f} vs "
                     f"{held['lpd_plain_fit']:.1f}, {held['lpd_plain_fit'] - h_cur.lpd:.2f} "
                     f"nats): compare with that fit before using it",)
    return LoopResult(model, m0, steps, cur, unexplained, fit, fit0, stop, ctx, comp, RULE,
                      noise_prior, input_json(rec), calibration_json(fit, ctx, model),
                      warnings, tuple(noise_rows), noise_adev, held, detectable)


#: nats of held-out log predictive density by which the final model may trail the plain
#: fit and still count as "not worse": two estimators of the same terms (GLS and least
#: squares) differ by 1e-6..1e-2 nats on a record where the loop adds nothing, a difference
#: no compensated output shows; 0.5 nats is a density ratio of 1.6 over the whole record.
PLAIN_TOLERANCE_NATS = 0.5


def _plain_check(ctx: Context, model: str, fit: ModelFit, h_final) -> dict:
    """The plain fit's terms by least squares, scored by the same held-out folds under the
    final noise model: the loop's output should not predict worse than what the user would
    otherwise run (within :data:`PLAIN_TOLERANCE_NATS`)."""
    if model not in DEFAULT_ORDERS:
        return {}
    terms = tuple(base_terms(ctx, model, DEFAULT_ORDERS[model]))
    plain = ModelFit(terms, ctx.block_design(list(terms)), fit.noise, np.zeros(0))
    h = holdout.score(ctx, plain, ols=True)
    return {"plain_fit": f"fogbayes fit -m {model} (orders {DEFAULT_ORDERS[model]}, least squares)",
            "lpd_plain_fit": h.lpd, "tolerance_nats": PLAIN_TOLERANCE_NATS,
            "final_not_worse_than_plain_fit": bool(h_final.lpd >= h.lpd - PLAIN_TOLERANCE_NATS)}


def _allan_story(rec, ctx: Context, steps: list[Step], fit: ModelFit):
    """ADEV misfit of the five-term model with and without the final noise model's
    Gauss-Markov components, then before/after each step (in the steps' detail) with them;
    unexplained if still > 3. Returns (unexplained rows, the noise model's misfits)."""
    t = ctx.cov.t
    dt = float(np.median(np.diff(t)))
    if np.max(np.diff(t)) > 1.5 * dt:
        return [], None  # gaps: the ADEV story needs uniform sampling
    fs = 1.0 / dt
    tmin = ctx.grid.dt
    noise = components(fit)
    five = adev_misfit(ctx.rate, fs, (), tau_min=tmin)
    before = adev_misfit(ctx.rate, fs, noise, tau_min=tmin)
    adev = None if five is None or before is None else {
        "five_term": five.misfit, "with_components": before.misfit, "tau_min_s": tmin}
    for i, s in enumerate(steps):
        after = adev_misfit(ctx.rate, fs, noise + [x.detail for x in steps[:i + 1]],
                            tau_min=tmin)
        if before is not None and after is not None:
            s.detail["adev_misfit_before"] = before.misfit
            s.detail["adev_misfit_after"] = after.misfit
            s.detail["adev_misfit_dex_before"] = before.rms_dex
            s.detail["adev_misfit_dex_after"] = after.rms_dex
        before = after
    if before is None or before.misfit <= 3.0:
        return [], adev
    z = np.abs(np.log(before.adev / before.adev_model))
    k = int(np.argmax(z))
    return [{"kind": "adev_misfit", "detail": {
        "misfit": before.misfit, "rms_dex": before.rms_dex, "tau_min_s": tmin,
        "worst_tau_s": float(before.tau[k]),
        "adev_deg_h": float(before.adev[k]), "model_adev_deg_h": float(before.adev_model[k]),
        "note": "five-term model plus the noise components and added terms misses the "
                "Allan deviation"}}], adev


def _read_published(steps: list[Step], fit: ModelFit, rec) -> None:
    """Each step's physical reading from the published calibration, so the loop's report
    and the calibration document state the same numbers for a term of the final model."""
    for s in steps:
        if s.term is None:
            continue
        where = [i for i, tm in enumerate(fit.terms) if tm == s.term]
        if not where:
            continue
        s.detail.update(_detail(fit, s.term, rec, column=sum(
            tm.n_cols for tm in fit.terms[:where[-1]])))


def _detail(fit: ModelFit, term, rec, column: int | None = None) -> dict:
    """``term``'s reading in ``fit``: its columns start at ``column`` (default: the last)."""
    k = term.n_cols
    a = fit.X.shape[1] - k if column is None else column
    beta = np.asarray(fit.beta)[a:a + k]
    se = np.sqrt(np.diag(fit.noise.cov_beta))[a:a + k]
    return describe(term, beta, se, t0=float(rec.time[0]))
