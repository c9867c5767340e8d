"""The closed loop's report: headline, the story step by step, figures (:mod:`fogbayes.plot.loop`).

Imports point one way: the report renders the plot module's figures; no plot imports a report.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..plot.loop import overview_figure, step_figure
from .effects import effect_phrase


def loop_intervals(res):
    """Bootstrap intervals of the loop's bias stability (1 s means, outliers left out).

    Returns ``(added, whole)``: base model -> final model (what the loop added) and raw
    output -> final model (the whole compensation), resampled with the same blocks.
    """
    from ..loop.metrics import BS_WINDOW_S
    from .bootstrap import stability_intervals

    ctx = res.context
    keep = ~np.asarray(ctx.outlier, bool)
    t = ctx.cov.t
    added = stability_intervals(res.initial_fit.residual, {"final": res.fit.residual}, t,
                                window_s=BS_WINDOW_S, keep=keep)["final"]
    whole = stability_intervals(ctx.rate, {"final": res.fit.residual}, t,
                                window_s=BS_WINDOW_S, keep=keep)["final"]
    return added, whole


def _what(res) -> str:
    """The recording line from the loop's own context (when no Recording is passed)."""
    from .html import fmt

    cov = res.context.cov
    n = cov.t.size
    dur = float(cov.t[-1] - cov.t[0]) if n > 1 else 0.0
    fs = 1.0 / float(np.median(np.diff(cov.t))) if n > 1 else float("nan")
    parts = [f"{fmt(dur / 3600, sig=3)} h at {fmt(fs)} Hz ({n} samples)"]
    if cov.T.size:
        parts.append(f"temperature {np.nanmin(cov.T[:, 0]):.1f} … {np.nanmax(cov.T[:, 0]):.1f} °C")
    return " · ".join(parts)


def loop_headline(res, rec=None):
    """The headline section of a loop report: what the loop added, with intervals."""
    from ..errors import FogbayesError
    from .headline import headline_section, improvement_verdict
    from .html import fmt

    final = " + ".join([res.model, *res.effects])
    model = (f"closed loop from the {res.model} base model; final model {final}"
             if res.steps else f"closed loop from the {res.model} base model; nothing added")
    what = None if rec is not None else _what(res)
    desc = [effect_phrase(st.effect, st.detail, st.covariates) for st in res.steps]
    try:
        added, whole = loop_intervals(res)
    except (ValueError, FogbayesError):  # fewer than three 1 s windows
        return headline_section(rec, model=model, what=what, verdict=(
            f"The loop added {'; '.join(desc) or 'nothing'}; the record is too short "
            "for a bias stability with an interval."))
    if res.steps:
        sentence, ok = improvement_verdict(added, f"The loop added {'; '.join(desc)}. This")
    else:
        sentence = (f"Nothing supported: the loop added no effect to {res.model} "
                    f"({res.stop.reason}). Bias stability stays {fmt(added.after.value)} deg/h.")
        ok = None
    rows = [(f"what the loop added: {res.model} → {final}",
             "before: residual of the base model; after: residual of the final model", added),
            (f"whole compensation: raw → {final}", "before: raw output", whole)]
    return headline_section(rec, model=model, rows=rows, verdict=sentence, ok=ok, what=what)


def _described(effect: str) -> str:
    """`` — <the effect's description>`` from the registry ("" if it has none)."""
    from ..effects import REGISTRY

    desc = getattr(REGISTRY.get(effect), "description", "")
    return f" — {desc}" if desc else ""


def loop_section(res):
    """A :class:`~fogbayes.render.html.Section` telling the loop's story."""
    from ..loop.noise_model import sentence as noise_model_sentence
    from .html import Cell, Section, fmt

    sec = Section("Closed loop")
    sec.text(f"Base model: {res.model}. Each step adds the candidate effect the evidence "
             f"supports and refits; the method (the acceptance rule) is at the end of this "
             f"section.")

    def bs(x):
        return x.bias_stability

    rows = [[Cell(f"base model: {res.model}"), res.initial.rms, bs(res.initial), res.initial.elpd]]
    rows += [[Cell(f"+ {s.effect}"), s.metrics_after.rms, bs(s.metrics_after),
              s.metrics_after.elpd] for s in res.steps]
    sec.table(["model", "RMS of 10 s residual means [deg/h]", "bias stability, 1 s means [deg/h]",
               "ELPD, PSIS-LOO [nats]"], rows,
              caption="higher ELPD = better predictions of held-out block means")
    sec.figure(overview_figure(res), caption="Residual of the base model and of the final "
                                              "model (10 s means).")
    for i, s in enumerate(res.steps):
        e = s.evidence
        what = _described(s.effect)
        if e.get("declared"):  # the user's: no test, no ranking of candidates
            sec.text(f"Step {i + 1}: declared {effect_phrase(s.effect, s.detail, s.covariates)}"
                     f"{what}. Added without a test; likelihood ratio 2 dlogL = "
                     f"{fmt(e['likelihood_ratio'])}. RMS {fmt(s.rms_before)} → "
                     f"{fmt(s.rms_after)} deg/h.")
            sec.figure(step_figure(res, i), caption=f"the residual {s.effect} was fitted to")
            continue
        sec.text(f"Step {i + 1}: added {effect_phrase(s.effect, s.detail, s.covariates)}{what}. "
                 f"Likelihood ratio 2 dlogL = {fmt(e['likelihood_ratio'])}, calibrated log10 p = "
                 f"{fmt(e['log10_p'], sig=3)} (family-wise {fmt(e['log10_p_familywise'], sig=3)}); "
                 f"ELPD gain {fmt(e['elpd_diff'])} ± {fmt(e['elpd_diff_se'], sig=3)} nats. "
                 f"RMS {fmt(s.rms_before)} → {fmt(s.rms_after)} deg/h.")
        if e.get("alternatives"):  # duels the data could not decide (fogbayes.loop.ranking)
            sec.note("Indistinguishable alternatives (the simpler was kept): " + "; ".join(
                f"{a['effect']} (2 dlogL alt - chosen "
                f"{a['d_2loglik_alternative_minus_chosen']:+.3g}, d ELPD "
                f"{a['elpd_diff_chosen_minus_alternative']:.3g} +- {a['elpd_diff_se']:.3g})"
                for a in e["alternatives"]) + (
                ". A chamber programme that separates them: fogbayes plan-chamber (docs/plan.md)"
                if all(a.get("separable_by_programme") for a in e["alternatives"]) else ""),
                ok=False)
        sec.table(["candidate effect", "screening 2 dlogL", "log10 p", "log10 p, family-wise"],
                  [[r["effect"], r["screen_lr"], Cell(fmt(r["log10_p"], sig=3)),
                    Cell(fmt(r["log10_p_familywise"], sig=3))]
                   for r in e["screening"]], caption="how the candidates ranked (log10 p = -2 "
                                                     "means p = 0.01)")
        sec.figure(step_figure(res, i), caption=f"the residual that justified {s.effect}")
    sec.note(f"Stopped: {res.stop.reason}.", ok=True)
    sec.text(noise_model_sentence(res.fit, res.noise_selection))
    h = res.holdout or {}
    for r in h.get("not_kept", []):
        sec.note(f"Not kept: {r['effect']} was supported by the evidence but predicted "
                 f"held-out time blocks worse (log predictive density {fmt(r['lpd'])} against "
                 f"{fmt(r['lpd_before'])} nats without it, standard error of the difference "
                 f"{fmt(r['diff_se'])}, over the {r['folds_judging']} of {r['folds']} folds "
                 f"that can judge it).", ok=False)
    if h:
        sec.text(f"Held-out check ({h['folds']} contiguous time folds, each predicted from the "
                 f"others): log predictive density {fmt(h['lpd_base'])} nats for the base model, "
                 f"{fmt(h['lpd_final'])} for the final one. The RMS and bias stability above "
                 f"are of the output with the deterministic terms subtracted; the noise model "
                 f"subtracts nothing.")
    if res.unexplained:
        def brief(u):
            items = [f"{k}={v}" for k, v in u["detail"].items()
                     if not isinstance(v, (list, np.ndarray))]
            return f"{u['kind']} ({', '.join(items)})"
        sec.note("Structure no candidate explains: " + "; ".join(map(brief, res.unexplained)),
                 ok=False)
    sec.details("Method: when the loop accepts a candidate effect", f"Rule: {res.rule}")
    return sec


def loop_report(res, path: str | Path, *, title: str = "Closed loop", rec=None) -> Path:
    """Write a stand-alone HTML report of a :class:`~fogbayes.loop.LoopResult`.

    It opens with the headline (what the loop added, bias stability with bootstrap
    intervals); ``rec`` (the Recording) adds its sensor and file to that block.
    """
    from .html import write

    return write(path, title, [loop_headline(res, rec), loop_section(res)])
