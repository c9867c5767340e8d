"""Residual against time and against each covariate, as binned means with 95 % intervals."""

from __future__ import annotations

import numpy as np

from .style import COLORS, escape_mathtext, new_figure


def binned_means(x: np.ndarray, r: np.ndarray, bins: int = 30):
    """Centres, means and 95 % half-widths (1.96 s/sqrt(n)) of ``r`` in equal-count bins of ``x``.

    The half-widths treat samples in a bin as independent: with colored noise they are too
    narrow, so read them as a guide for the eye, not as a test.
    """
    order = np.argsort(x, kind="stable")
    groups = [g for g in np.array_split(order, min(bins, max(1, x.size // 5))) if g.size > 1]
    c = np.array([x[g].mean() for g in groups])
    m = np.array([r[g].mean() for g in groups])
    h = np.array([1.96 * r[g].std(ddof=1) / np.sqrt(g.size) for g in groups])
    return c, m, h


def plot_residuals(time: np.ndarray, residual: np.ndarray, covariates: dict[str, np.ndarray], *,
                   unit: str = "deg/h", window_s: float = 10.0, color: str | None = None):
    """One panel against time (``window_s`` block means) and one per covariate (binned means).

    Every panel has its y label with the unit; ``color`` is the model's colour
    (:func:`fogbayes.plot.style.model_color`) so the residual reads as that model's.
    """
    panels = 1 + len(covariates)
    fig, axes = new_figure(1, panels, figsize=(3.3 * panels, 3.0), squeeze=False)
    axes = axes[0]
    dt = float(np.median(np.diff(time))) if time.size > 1 else 1.0
    k = max(1, int(round(window_s / dt)))
    n = (time.size // k) * k
    if n:
        axes[0].plot(time[:n].reshape(-1, k).mean(1) / 3600, residual[:n].reshape(-1, k).mean(1),
                     color=color or COLORS["data"], lw=0.7)
    axes[0].set_xlabel("time [h]")
    axes[0].set_ylabel(f"residual, {window_s:g} s means [{unit}]")
    for ax, (name, x) in zip(axes[1:], covariates.items()):
        c, m, h = binned_means(np.asarray(x, float), np.asarray(residual, float))
        ax.errorbar(c, m, yerr=h, fmt="o", ms=3, color=color or COLORS["after"], capsize=1.5)
        ax.axhline(0.0, color="k", lw=0.6)
        ax.set_xlabel(escape_mathtext(name))
        ax.set_ylabel(f"binned mean residual [{unit}]")
    return fig
