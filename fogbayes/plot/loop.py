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
from .style import COLORS, new_figure


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
    fig, ax = new_figure(1, 2, figsize=(10, 3.4))
    ax[0].plot(tb / 3600, rb, ".", ms=2, color=COLORS["data"], label="residual before (10 s means)")
    if s.term is not None:
        # what the step changed in the model: the part of the old residual it explains
        contrib = before.residual - s.fit.residual
        tc, cb = _blocks(t, contrib, out)
        ax[0].plot(tc / 3600, cb, color=COLORS["model"], label=f"model change: + {s.effect}")
        drv = columns(s.term, ctx.cov)[:, 0]
        _, db = _blocks(t, drv, out)
        ax[1].plot(db, rb, ".", ms=2, color=COLORS["data"])
        ax[1].plot(db, cb, ".", ms=2, color=COLORS["model"])
        ax[1].set_xlabel(f"{s.term.kind} column (scaled)")
        ax[1].set_ylabel("deg/h")
        ax[1].set_title("residual against the added term's driver")
    else:  # a noise term: the Allan deviation it was needed for
        from ..loop.adev_misfit import adev_misfit

        fs = 1.0 / float(np.median(np.diff(t)))
        a0 = adev_misfit(ctx.rate, fs, [x for x in res.steps[:i] if x.term is None or
                                        x.effect == "periodic"], tau_min=ctx.grid.dt)
        a1 = adev_misfit(ctx.rate, fs, [x for x in res.steps[:i + 1] if x.term is None or
                                        x.effect == "periodic"], tau_min=ctx.grid.dt)
        if a0 is not None and a1 is not None:
            ax[1].loglog(a0.tau, a0.adev, "o", ms=3, color=COLORS["data"], label="ADEV")
            ax[1].loglog(a0.tau, a0.adev_model, color=COLORS["data"], label="model before")
            ax[1].loglog(a1.tau, a1.adev_model, color=COLORS["model"], label=f"+ {s.effect}")
            ax[1].set_xlabel("tau (s)")
            ax[1].set_ylabel("deg/h")
            ax[1].legend()
        ax[1].set_title("Allan deviation: the misfit the noise term removes")
    ax[0].set_xlabel("time (h)")
    ax[0].set_ylabel("deg/h")
    ax[0].set_title(f"step {i + 1}: {s.effect}")
    ax[0].legend(loc="best")
    return fig


def overview_figure(res):
    """10 s block residual of the initial and the final model against time."""
    ctx = res.context
    fig, ax = new_figure()
    for fit, lab, col in ((res.initial_fit, f"initial {res.model}", COLORS["data"]),
                          (res.fit, "final", COLORS["after"])):
        tb, rb = _blocks(ctx.cov.t, fit.residual, ctx.outlier)
        ax.plot(tb / 3600, rb, lw=0.8, color=col, label=lab)
    ax.set_xlabel("time (h)")
    ax.set_ylabel("residual, 10 s means (deg/h)")
    ax.legend()
    return fig


def loop_section(res):
    """A :class:`~fogbayes.report.html.Section` telling the loop's story."""
    from ..report.html import Section

    sec = Section("Closed loop")
    sec.text(f"Base model: {res.model}. Rule: {res.rule}")
    rows = [["initial", res.initial.rms, res.initial.bias_stability, res.initial.elpd]]
    rows += [[f"+ {s.effect}", s.metrics_after.rms, s.metrics_after.bias_stability,
              s.metrics_after.elpd] for s in res.steps]
    sec.table(["model", "RMS 10 s (deg/h)", "bias stability 1 s (deg/h)", "ELPD (LOO)"], rows)
    sec.figure(overview_figure(res), caption="Residual before and after the loop")
    for i, s in enumerate(res.steps):
        e = s.evidence
        sec.text(f"Step {i + 1}: added {s.effect} ({', '.join(s.covariates)}). "
                 f"2 dlogL = {e['likelihood_ratio']:.4g}, log10 p (calibrated) = "
                 f"{e['log10_p']:.3g}, family-wise {e['log10_p_familywise']:.3g}; "
                 f"d ELPD = {e['elpd_diff']:.4g} +- {e['elpd_diff_se']:.3g}. "
                 f"RMS {s.rms_before:.4g} -> {s.rms_after:.4g} deg/h.")
        if e.get("alternatives"):  # duels the data could not decide (fogbayes.loop.ranking)
            sec.note("Indistinguishable alternatives (the simpler was kept): " + "; ".join(
                f"{a['effect']} (2 dlogL alt - chosen "
                f"{a['d_2loglik_alternative_minus_chosen']:+.3g}, d ELPD "
                f"{a['elpd_diff_chosen_minus_alternative']:.3g} +- {a['elpd_diff_se']:.3g})"
                for a in e["alternatives"]), ok=False)
        sec.table(["candidate", "screening 2 dlogL", "log10 p", "log10 p family-wise"],
                  [[r["effect"], r["screen_lr"], r["log10_p"], r["log10_p_familywise"]]
                   for r in e["screening"]], caption="how the candidates ranked")
        sec.figure(step_figure(res, i), caption=f"the residual that justified {s.effect}")
    sec.note(f"Stopped: {res.stop.reason}.", ok=True)
    if res.unexplained:
        def brief(u):
            items = [f"{k}={v}" for k, v in u["detail"].items()
                     if not isinstance(v, (list, np.ndarray))]
            return f"{u['kind']} ({', '.join(items)})"
        sec.note("Structure no candidate explains: " + "; ".join(map(brief, res.unexplained)),
                 ok=False)
    return sec


def loop_report(res, path: str | Path, *, title: str = "Closed loop") -> Path:
    """Write a stand-alone HTML report of a :class:`~fogbayes.loop.LoopResult`."""
    from ..report.html import write

    return write(path, title, [loop_section(res)])
