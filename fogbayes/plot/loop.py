"""Figures and the report section of the closed loop: the story, step by step.

For every added effect: the residual of the model *before* the step (10 s block means)
against time with the added term's fitted contribution on top, and the same residual
against the term's own driver (a partial-residual plot) -- the residual that justified
the addition. Noise steps show the autocorrelation of the whitened residual instead.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..diagnose.terms import columns
from ..preprocess.blocks import block_average
from .style import COLORS, LEGEND_RIGHT, model_color, new_figure

_DRIVER_LABELS = {"rate": "dT/dt [°C/min]", "rate_poly": "dT/dt [°C/min]",
                  "hysteresis": "dT/dt [°C/min]", "drift_lin": "time [h]",
                  "drift_exp": "time [h]", "step": "time [h]", "drift_tpoly": "time [h]",
                  "omega_poly": "input rate [°/s]", "omega_abs": "input rate [°/s]",
                  "omega_tpoly": "input rate [°/s]"}


def driver(term, cov):
    """The physical variable a term depends on, per sample, and its axis label with unit.

    The design column itself is centred and scaled (dimensionless); a reader wants the
    temperature rate in °C/min or the time in hours on the axis.
    """
    k, p = term.kind, term.params
    if k in ("rate", "rate_poly", "hysteresis") and cov.Tdot is not None:
        return np.asarray(cov.Tdot, float), _DRIVER_LABELS[k]
    if k in ("drift_lin", "drift_exp", "step", "drift_tpoly"):
        return np.asarray(cov.t, float) / 3600.0, _DRIVER_LABELS[k]
    if k.startswith("omega") and cov.omega is not None:
        return np.asarray(cov.omega, float), _DRIVER_LABELS[k]
    if k in ("tpoly", "lag", "play") and "channel" in p:
        ch = p["channel"]
        j = ch if isinstance(ch, int) else list(cov.names).index(ch)
        name = cov.names[j] if j < len(cov.names) else "T"
        return np.asarray(cov.T[:, j], float), f"{name} [°C]"
    if k == "gradient":
        ja = p["a"] if isinstance(p["a"], int) else list(cov.names).index(p["a"])
        jb = p["b"] if isinstance(p["b"], int) else list(cov.names).index(p["b"])
        return (np.asarray(cov.T[:, jb] - cov.T[:, ja], float),
                f"{cov.names[jb]} - {cov.names[ja]} [°C]")
    if k == "periodic":
        return (np.asarray(cov.t, float) * float(p["frequency"])) % 1.0, \
            f"phase of the {1.0 / float(p['frequency']):.4g} s period [cycles]"
    return columns(term, cov)[:, 0], f"{k} term (centred and scaled, no unit)"


def _blocks(t, x, outlier, window=10.0):
    b = block_average(x, window, time=t, partial="keep", mask=outlier)
    ok = np.isfinite(b.mean)
    return b.time[ok], b.mean[ok]


def step_figure(res, i: int):
    """Residual before step ``i`` and the contribution of the term it added."""
    ctx, s = res.context, res.steps[i]
    before = res.steps[i - 1].fit if i > 0 else res.initial_fit
    t, out = ctx.cov.t, ctx.outlier
    tb, rb = _blocks(t, before.residual, out)
    fig, ax = new_figure(1, 2, figsize=(11, 3.4))
    ax[0].plot(tb / 3600, rb, ".", ms=2, color=COLORS["data"], label="residual before\n(10 s means)")
    # what the step changed in the model: the part of the old residual it explains
    contrib = before.residual - s.fit.residual
    tc, cb = _blocks(t, contrib, out)
    ax[0].plot(tc / 3600, cb, color=model_color("loop"), label=f"model change:\n+ {s.effect}")
    drv, dlabel = driver(s.term, ctx.cov)
    _, db = _blocks(t, drv, out)
    ax[1].plot(db, rb, ".", ms=2, color=COLORS["data"], label="residual before")
    ax[1].plot(db, cb, ".", ms=2, color=model_color("loop"), label=f"+ {s.effect}")
    ax[1].set_xlabel(dlabel)
    ax[1].set_ylabel("10 s means [deg/h]")
    ax[1].set_title("residual against the added term's driver")
    ax[1].legend(**LEGEND_RIGHT)
    ax[0].set_xlabel("time [h]")
    ax[0].set_ylabel("10 s means [deg/h]")
    ax[0].set_title(f"step {i + 1}: {s.effect}")
    ax[0].legend(loc="upper center", bbox_to_anchor=(0.5, -0.22), ncol=2, borderaxespad=0.0)
    return fig


def overview_figure(res):
    """10 s block residual of the initial and the final model against time."""
    ctx = res.context
    fig, ax = new_figure(figsize=(8.5, 3.4))
    final = " + ".join([res.model, *res.effects]) if res.steps else f"{res.model} (nothing added)"
    for fit, lab, col in ((res.initial_fit, f"base model: {res.model}", model_color(res.model)),
                          (res.fit, f"after the loop:\n{final}", model_color("loop"))):
        tb, rb = _blocks(ctx.cov.t, fit.residual, ctx.outlier)
        ax.plot(tb / 3600, rb, lw=0.8, color=col, label=lab)
    ax.set_xlabel("time [h]")
    ax.set_ylabel("residual, 10 s means [deg/h]")
    ax.legend(**LEGEND_RIGHT)
    return fig


def loop_intervals(res):
    """Bootstrap intervals of the loop's bias stability (1 s means, outliers left out).

    Returns ``(added, whole)``: base model -> final model (what the loop added) and raw
    output -> final model (the whole compensation), resampled with the same blocks.
    """
    from ..loop.metrics import BS_WINDOW_S
    from ..report.bootstrap import stability_intervals

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
    from ..report.html import fmt

    cov = res.context.cov
    n = cov.t.size
    dur = float(cov.t[-1] - cov.t[0]) if n > 1 else 0.0
    fs = 1.0 / float(np.median(np.diff(cov.t))) if n > 1 else float("nan")
    parts = [f"{fmt(dur / 3600, sig=3)} h at {fmt(fs)} Hz ({n} samples)"]
    if cov.T.size:
        parts.append(f"temperature {np.nanmin(cov.T[:, 0]):.1f} … {np.nanmax(cov.T[:, 0]):.1f} °C")
    return " · ".join(parts)


def _unit_from_key(key: str) -> str:
    """``'deg_h_per_degC_per_min'`` -> ``'deg/h per (°C/min)'`` (units spelled in JSON keys)."""
    def one(u):
        return {"deg_h": "deg/h", "degC": "°C", "deg_s": "°/s", "min": "min", "s": "s",
                "h": "h"}.get(u, u.replace("_", "/"))
    num, *den = key.split("_per_")
    if not den:
        return one(num)
    d = "/".join(one(x) for x in den)
    return f"{one(num)} per ({d})" if len(den) > 1 else f"{one(num)} per {d}"


def loop_headline(res, rec=None):
    """The headline section of a loop report: what the loop added, with intervals."""
    from ..errors import FogbayesError
    from ..report.headline import headline_section, improvement_verdict
    from ..report.html import fmt

    final = " + ".join([res.model, *res.effects])
    model = (f"closed loop from the {res.model} base model; final model {final}"
             if res.steps else f"closed loop from the {res.model} base model; nothing added")
    what = None if rec is not None else _what(res)
    try:
        added, whole = loop_intervals(res)
    except (ValueError, FogbayesError):  # fewer than three 1 s windows
        return headline_section(rec, model=model, what=what, verdict=(
            f"The loop added {', '.join(res.effects) or 'nothing'}; the record is too short "
            "for a bias stability with an interval."))
    if res.steps:
        desc = []
        for st in res.steps:
            coef = next((v for k, v in st.detail.items() if k.startswith("coefficient_")
                         and isinstance(v, dict) and "value" in v), None)
            unit = next((_unit_from_key(k[len("coefficient_"):]) for k in st.detail
                         if k.startswith("coefficient_")), "")
            c = (f", coefficient {fmt(coef['value'])} ± {fmt(coef.get('stderr'), sig=2)} {unit}"
                 if coef else "")
            desc.append(f"{st.effect} ({', '.join(st.covariates)}{c})")
        sentence, ok = improvement_verdict(added, f"The loop added {'; '.join(desc)}. This")
    else:
        sentence = (f"Nothing supported: the loop added no effect to {res.model} "
                    f"({res.stop.reason}). Bias stability stays {fmt(added.after.value)} deg/h.")
        ok = None
    rows = [(f"what the loop added: {res.model} → {final}",
             "before: residual of the base model; after: residual of the final model", added),
            (f"whole compensation: raw → {final}", "before: raw output", whole)]
    return headline_section(rec, model=model, rows=rows, verdict=sentence, ok=ok, what=what)


def loop_section(res):
    """A :class:`~fogbayes.report.html.Section` telling the loop's story."""
    from ..loop.noise_model import sentence as noise_model_sentence
    from ..report.html import Cell, Section, fmt

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
        sec.text(f"Step {i + 1}: added {s.effect} ({', '.join(s.covariates)}). "
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
                if {s.effect, *(a["effect"] for a in e["alternatives"])} <= {
                    "thermal_lag", "temperature_gradient", "temperature_rate"} else ""),
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
    from ..report.html import write

    return write(path, title, [loop_headline(res, rec), loop_section(res)])
