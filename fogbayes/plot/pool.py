"""Forest plot of a pool: each unit alone and pooled, against the population."""

from __future__ import annotations

import numpy as np
from matplotlib.ticker import FuncFormatter, LogLocator, MaxNLocator, NullFormatter

from .style import COLORS, LEGEND_RIGHT, escape_mathtext, model_color, new_figure

TERM_NAMES = {"Q": "Q quantization", "N": "N angle random walk", "B": "B bias instability",
              "K": "K rate random walk", "R": "R rate ramp"}
#: margin either side of what a panel shows: this share of its log span (and a little more)
_PAD = 0.12
#: how far below an unresolved population's bound its panel reaches
_BOUND_SPAN = 30.0


def _limits(pool: dict, t: str) -> tuple[float, float]:
    """The x range of term ``t``'s panel: every number the panel states (interval ends,
    estimates, upper bounds, the population band; for a term the population does not
    resolve down to _BOUND_SPAN below its bound: bars run to the edge), padded by _PAD of
    its log span, so that neither a narrow nor a wide set of intervals meets the edge. Lower ends that
    are 0 or the prior's (unresolved) do not stretch the axis."""
    pop = pool["population"][t]
    vals = []
    if pop.get("resolved", True):
        vals += [pop["median"]["low"], pop["median"]["high"], pop["new_unit"]["low"],
                 pop["new_unit"]["high"]]
    else:  # bars from the edge (towards 0) to the bound: the edge 1.5 decades below it
        vals += [pop["median"]["upper"], pop["new_unit"]["upper"],
                 pop["median"]["upper"] / _BOUND_SPAN]
    for u in pool["units"]:
        single, pooled = u["terms"][t]["single"], u["terms"][t]["pooled"]
        vals += [single["high"]] + ([single["low"], single["value"]] if single["resolved"] else [])
        vals += [pooled["upper"]] if "upper" in pooled else [pooled["low"], pooled["high"]]
    vals = np.array([v for v in vals if v is not None and np.isfinite(v) and v > 0])
    lo, hi = float(vals.min()), float(vals.max())
    pad = np.exp(_PAD * np.log(hi / lo) + 0.002)
    return lo / pad, hi * pad


def _format_axis(ax, lo: float, hi: float) -> None:
    """Log x axis with labels that do not collide: at most three plain ticks within a
    decade, 1-2-5 or 1-3 ticks over up to 2.5 decades, decades (at most ~5) beyond."""
    ax.set_xscale("log")
    ax.set_xlim(lo, hi)
    if hi / lo > 10.0:
        decades = np.log10(hi / lo)
        # a label such as "0.005" takes ~0.35 of a 3-inch panel's decade when it spans 2:
        # 1-2-5 ticks up to 1.3 decades, 1-3 up to 2.5, decades beyond
        subs = (1.0, 2.0, 5.0) if decades <= 1.3 else (1.0, 3.0) if decades <= 2.5 else (1.0,)
        ax.xaxis.set_major_locator(LogLocator(base=10.0, subs=subs, numticks=12 if
                                              decades <= 2.5 else int(min(decades, 5)) + 2))
        ax.xaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:.0e}".replace("e-0", "e-")
                                                   .replace("e+0", "e") if v < 1e-3 or v >= 1e4
                                                   else f"{v:g}"))
    else:
        ax.xaxis.set_major_locator(MaxNLocator(nbins=3))
        ax.xaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:.3g}"))
    ax.xaxis.set_minor_formatter(NullFormatter())


def pool_figure(pool: dict, *, title: str = ""):
    """One panel per pooled term: per-unit 90 % intervals alone (grey) and pooled (colour),
    the population median's interval (band) and a new unit's 90 % range (dashed); flagged
    units in red. A term not resolved (by a unit, or by the population) is drawn as an upper
    bound: a bar from the panel's left edge (an arrow) to its 95 % bound, never as a value.
    Log x axis: the model is in log space; each panel spans what it states."""
    terms = pool["terms"]
    units = pool["units"]
    n = len(units)
    fig, axes = new_figure(1, len(terms), figsize=(3.3 * len(terms) + 1.9, 1.3 + 0.36 * n),
                           sharey=True, squeeze=False)
    ypos = np.arange(n)[::-1]
    for ax, t in zip(axes[0], terms):
        pop = pool["population"][t]
        lo, hi = _limits(pool, t)
        edge = lo * 1.0001  # bars of upper bounds start at the edge, their arrow inside it
        unit = pop["median"]["unit"]
        if pop.get("resolved", True):
            med = pop["median"]
            ax.axvspan(med["low"], med["high"], color=COLORS["band"], alpha=0.15,
                       label="population median (90 %)")
            ax.axvline(med["value"], color=COLORS["band"], lw=1.0)
            for x in (pop["new_unit"]["low"], pop["new_unit"]["high"]):
                ax.axvline(x, color=COLORS["band"], lw=0.9, ls="--")
            ax.plot([], [], color=COLORS["band"], lw=0.9, ls="--", label="a new unit (90 %)")
        else:
            ax.axvspan(lo, pop["median"]["upper"], color=COLORS["band"], alpha=0.08,
                       hatch="//", label="population median: bound (95 %)")
            ax.text(0.98, 0.98, "not resolved", transform=ax.transAxes, ha="right", va="top",
                    fontsize=8, color=COLORS["band"])
        for y, u in zip(ypos, units):
            single, pooled = u["terms"][t]["single"], u["terms"][t]["pooled"]
            first = y == ypos[0]
            if single["resolved"]:
                ax.plot([single["low"], single["high"]], [y + 0.18] * 2, color=COLORS["data"],
                        lw=2.2, solid_capstyle="butt", label="unit alone" if first else None)
                ax.plot(single["value"], y + 0.18, "o", ms=3.5, color=COLORS["data"])
            else:  # an upper bound only: the interval reaches 0
                ax.plot([edge, single["high"]], [y + 0.18] * 2, color=COLORS["data"], lw=2.2,
                        solid_capstyle="butt", label="unit alone" if first else None)
                ax.plot(edge, y + 0.18, "<", ms=5, color=COLORS["data"], clip_on=False)
                ax.plot(single["high"], y + 0.18, "|", ms=7, color=COLORS["data"])
            c = model_color("loop") if u["outlier"]["flagged"] else model_color("allan")
            if "upper" in pooled:
                ax.plot([edge, pooled["upper"]], [y - 0.18] * 2, color=c, lw=2.2,
                        solid_capstyle="butt", label="pooled" if first else None)
                ax.plot(edge, y - 0.18, "<", ms=5, color=c, clip_on=False)
                ax.plot(pooled["upper"], y - 0.18, "|", ms=7, color=c)
            else:
                ax.plot([pooled["low"], pooled["high"]], [y - 0.18] * 2, color=c, lw=2.2,
                        solid_capstyle="butt", label="pooled" if first else None)
                ax.plot(pooled["value"], y - 0.18, "o", ms=3.5, color=c)
        _format_axis(ax, lo, hi)
        ax.set_ylim(-0.7, n - 0.3)
        ax.set_xlabel(f"{TERM_NAMES.get(t, t)}\n[{unit}]")
    axes[0][0].set_yticks(ypos, [escape_mathtext(u["name"])
                                 + (" (flagged)" if u["outlier"]["flagged"] else "")
                                 for u in units])
    handles = {}
    for ax in axes[0]:  # one legend for all panels, each entry once
        for h, lab in zip(*ax.get_legend_handles_labels()):
            handles.setdefault(lab, h)
    axes[0][-1].legend(list(handles.values()), list(handles), **LEGEND_RIGHT)
    if title:
        fig.suptitle(escape_mathtext(title))
    return fig
