"""Figures of the closed loop, step by step (report section :mod:`fogbayes.render.loop`).

Per added effect: the residual before the step against time with the term's contribution, and
against the term's driver (partial residual); time-driven terms show before/after; noise steps
the whitened residual's ACF.
"""

from __future__ import annotations


import numpy as np

from ..effects.kinds import KINDS, kind_of
from ..effects.terms import columns
from ..preprocess.blocks import block_average
from .style import COLORS, LEGEND_RIGHT, model_color, new_figure

#: term kinds whose driver is time: their partial-residual panel would repeat the time panel
TIME_DRIVEN = tuple(k for k, v in KINDS.items() if v.time_driven)


def driver(term, cov):
    """The physical variable a term depends on, per sample, and its axis label with unit.

    The design column itself is centred and scaled (dimensionless); a reader wants the
    temperature rate in °C/min or the time in hours on the axis.
    """
    k, p = term.kind, term.params
    kind = kind_of(k)
    d = kind.driver
    if d == "dT/dt" and cov.Tdot is not None:
        return np.asarray(cov.Tdot, float), kind.driver_label
    if d == "time":
        return np.asarray(cov.t, float) / 3600.0, kind.driver_label
    if d == "input_rate" and cov.omega is not None:
        return np.asarray(cov.omega, float), kind.driver_label
    if d == "channel" and "channel" in p:
        ch = p["channel"]
        j = ch if isinstance(ch, int) else list(cov.names).index(ch)
        name = cov.names[j] if j < len(cov.names) else "T"
        return np.asarray(cov.T[:, j], float), f"{name} [°C]"
    if d == "gradient":
        ja = p["a"] if isinstance(p["a"], int) else list(cov.names).index(p["a"])
        jb = p["b"] if isinstance(p["b"], int) else list(cov.names).index(p["b"])
        return (np.asarray(cov.T[:, jb] - cov.T[:, ja], float),
                f"{cov.names[jb]} - {cov.names[ja]} [°C]")
    if d == "phase":
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
    if kind_of(s.term.kind).time_driven:
        # the driver is time itself: against it the first panel would be drawn again, so
        # the second shows what the step leaves, the residual after it
        ta, ra = _blocks(t, s.fit.residual, out)
        ax[1].plot(tb / 3600, rb, ".", ms=2, color=COLORS["data"], label="residual before")
        ax[1].plot(ta / 3600, ra, ".", ms=2, color=model_color("loop"),
                   label=f"residual after\n+ {s.effect}")
        ax[1].set_xlabel("time [h]")
        ax[1].set_title(f"residual before and after adding {s.effect}")
    else:
        # partial residual: the residual after the step plus the added term's own part.
        # (before - after would add the refit's shift of the base terms, which splits the
        # points of one driver value by temperature, e.g. two cooling ramps into branches)
        drv, dlabel = driver(s.term, ctx.cov)
        _, db = _blocks(t, drv, out)
        j = sum(tm.n_cols for tm in s.fit.terms[:list(s.fit.terms).index(s.term)])
        own = columns(s.term, ctx.cov) @ s.fit.beta[j:j + s.term.n_cols]
        r_after = s.fit.residual - np.mean(s.fit.residual[~out])
        _, pb = _blocks(t, r_after + own, out)
        _, ob = _blocks(t, own, out)
        ax[1].plot(db, pb, ".", ms=2, color=COLORS["data"],
                   label="residual after\n+ the term's part")
        ax[1].plot(db, ob, ".", ms=2, color=model_color("loop"), label=f"+ {s.effect}")
        ax[1].set_xlabel(dlabel)
        ax[1].set_title("partial residual against the added term's driver")
    ax[1].set_ylabel("10 s means [deg/h]")
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
