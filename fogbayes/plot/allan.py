"""Log-log Allan deviation figure from an ``allan`` fit document (renders only).

Draws the measured ADEV with its confidence bars, the fitted total and each term's line,
and the posterior band (and predictive band of the estimates) when the fit has them.
Everything comes from the document of :func:`fogbayes.allan.workflow.fit_recording`.
"""

from __future__ import annotations

import numpy as np

from .style import COLORS, escape_mathtext, new_figure

# One hue family per term (purple, green, orange, blue; the ramp near-black), hues at least
# 45 degrees apart and a CIE76 colour difference of at least 35 from each other, the data
# grey and the fit's red; each term also has its own dash pattern, for print without colour.
_TERM_COLORS = {"Q": "#7b3294", "N": "#1a9850", "B": "#e08214", "K": "#2166ac", "R": "#222222"}
_TERM_DASHES = {"Q": (0, (1, 1.5)), "N": (0, (5, 2)), "B": (0, (3, 1.5, 1, 1.5)),
                "K": (0, (8, 2, 2, 2)), "R": (0, (2, 2))}
_TERM_NAMES = {"Q": "quantization", "N": "angle random walk", "B": "bias instability",
               "K": "rate random walk", "R": "rate ramp"}


def allan_figure(doc: dict, *, title: str | None = None):
    """The figure (a matplotlib Figure) for an ``allan`` document, or one panel per axis for
    a multi-axis document (:mod:`fogbayes.data.axes_doc`)."""
    from ..data.axes_doc import is_axes_document

    if not is_axes_document(doc):
        fig, ax = new_figure(figsize=(10.0, 5.4))
        _draw(ax, doc, title or f"Allan deviation, {doc.get('sensor_id', '')}".rstrip(", "))
        return fig
    axes = doc["axes"]
    fig, panels = new_figure(nrows=len(axes), figsize=(10.0, 5.0 * len(axes)), squeeze=False)
    for ax, (name, sub) in zip(panels[:, 0], axes.items()):
        sensor = sub.get("sensor_id") or ""
        _draw(ax, sub, f"{title or 'Allan deviation'}, axis {name}" + (f": {sensor}" if sensor else ""))
    return fig


def _draw(ax, doc: dict, title: str) -> None:
    """One Allan document on ``ax``: measured ADEV with its bars, fit, terms, bands."""
    tau, dev = np.asarray(doc["tau"], float), np.asarray(doc["adev"], float)
    lo, hi = np.asarray(doc["adev_low"], float), np.asarray(doc["adev_high"], float)
    ax.errorbar(tau, dev, yerr=[dev - lo, hi - dev], fmt="o", ms=3, color=COLORS["data"],
                ecolor=COLORS["data"], elinewidth=0.8, capsize=1.5,
                label=f"ADEV ({doc.get('ci', 0.9):.0%} interval)")
    fit = doc.get("fit", {})
    rng = fit.get("range") or {}
    if rng.get("taus_left_out"):
        ax.axvspan(tau[0] / 1.3, np.sqrt(rng["tau_min"] * tau[rng["taus_left_out"] - 1]),
                   color=COLORS["data"], alpha=0.1, lw=0,
                   label=f"left out of the fit ({rng['taus_left_out']} taus)")
    band = fit.get("band")
    if band:
        ax.fill_between(band["tau"], band["adev_low"], band["adev_high"], color=COLORS["band"],
                        alpha=0.2, lw=0, label="posterior band (model)")
    pred = fit.get("predictive")
    if pred:
        ax.vlines(pred["tau"], pred["adev_low"], pred["adev_high"], color=COLORS["band"],
                  lw=3, alpha=0.25, label="posterior predictive (estimates)")
    curves = fit.get("curves")
    if curves:
        ax.plot(curves["tau"], curves["total"], color=COLORS["model"],
                label=f"fit ({fit.get('method', '')})")
        for t, y in curves["terms"].items():
            ax.plot(curves["tau"], y, ls=_TERM_DASHES[t], lw=1.1, color=_TERM_COLORS[t],
                    label=_label(t, fit["terms"].get(t)))
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_ylim(0.5 * np.nanmin(lo), 2.0 * np.nanmax(hi))
    ax.set_xlabel("averaging time tau (s)")
    ax.set_ylabel(f"Allan deviation ({doc.get('unit', 'deg/h')})")
    ax.set_title(escape_mathtext(title))
    # below the plot, two columns: the plot keeps the figure's width
    # (anchored a fixed 36 points under the axes: below the tick labels and the axis label
    # whatever the panel's height)
    from matplotlib.transforms import offset_copy

    ax.legend(loc="upper center", bbox_to_anchor=(0.5, 0.0), ncol=2, borderaxespad=0,
              bbox_transform=offset_copy(ax.transAxes, fig=ax.figure, y=-36, units="points"),
              columnspacing=1.2, handlelength=2.6)


def _label(term: str, est: dict | None) -> str:
    if not est:
        return _TERM_NAMES[term]
    return (f"{term} = {est['value']:.3g} [{est['low']:.3g}, {est['high']:.3g}] "
            f"{est['unit']} ({_TERM_NAMES[term]})")
