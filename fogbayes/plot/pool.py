"""Forest plot of a pool: each unit alone and pooled, against the population."""

from __future__ import annotations

import numpy as np
from matplotlib.ticker import FuncFormatter, MaxNLocator, NullFormatter

from .style import COLORS, LEGEND_RIGHT, escape_mathtext, model_color, new_figure

TERM_NAMES = {"Q": "Q quantization", "N": "N angle random walk", "B": "B bias instability",
              "K": "K rate random walk", "R": "R rate ramp"}


def pool_figure(pool: dict, *, title: str = ""):
    """One panel per pooled term: per-unit 90 % intervals alone (grey) and pooled (colour),
    the population median's interval (band) and a new unit's 90 % range (dashed); flagged
    units in red. Log x axis: the model is in log space."""
    terms = pool["terms"]
    units = pool["units"]
    n = len(units)
    fig, axes = new_figure(1, len(terms), figsize=(3.2 * len(terms) + 1.6, 0.9 + 0.32 * n),
                           sharey=True, squeeze=False)
    ypos = np.arange(n)[::-1]
    for ax, t in zip(axes[0], terms):
        pop = pool["population"][t]
        med = pop["median"]
        ax.axvspan(med["low"], med["high"], color=COLORS["band"], alpha=0.15,
                   label="population median (90 %)")
        ax.axvline(med["value"], color=COLORS["band"], lw=1.0)
        for x in (pop["new_unit"]["low"], pop["new_unit"]["high"]):
            ax.axvline(x, color=COLORS["band"], lw=0.9, ls="--")
        ax.plot([], [], color=COLORS["band"], lw=0.9, ls="--", label="a new unit (90 %)")
        for y, u in zip(ypos, units):
            single, pooled = u["terms"][t]["single"], u["terms"][t]["pooled"]
            lo = single["low"] if single["low"] > 0 else single["value"]
            ax.plot([lo, single["high"]], [y + 0.18] * 2, color=COLORS["data"], lw=2.2,
                    solid_capstyle="butt", label="unit alone" if y == ypos[0] else None)
            ax.plot(single["value"], y + 0.18, "o", ms=3.5, color=COLORS["data"])
            if not single["resolved"]:  # an upper bound only: the interval reaches 0
                ax.plot(lo, y + 0.18, "<", ms=5, color=COLORS["data"])
            c = model_color("loop") if u["outlier"]["flagged"] else model_color("allan")
            ax.plot([pooled["low"], pooled["high"]], [y - 0.18] * 2, color=c, lw=2.2,
                    solid_capstyle="butt", label="pooled" if y == ypos[0] else None)
            ax.plot(pooled["value"], y - 0.18, "o", ms=3.5, color=c)
        ax.set_xscale("log")
        ax.xaxis.set_major_locator(MaxNLocator(nbins=3))
        ax.xaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:.3g}"))
        ax.xaxis.set_minor_formatter(NullFormatter())
        ax.set_xlabel(f"{TERM_NAMES.get(t, t)} [{med['unit']}]")
    axes[0][0].set_yticks(ypos, [escape_mathtext(u["name"]) + (" (flagged)" if u["outlier"]["flagged"] else "")
                                 for u in units])
    axes[0][-1].legend(**LEGEND_RIGHT)
    if title:
        fig.suptitle(escape_mathtext(title))
    return fig
