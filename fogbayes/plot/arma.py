"""Figures of an ARMA drift analysis (paper 002, Figs. 3-5); every function returns a Figure.

Renders what :func:`fogbayes.arma.workflow.analyse_recording` computed; computes nothing new.
"""

from __future__ import annotations

import numpy as np

from .style import COLORS, LEGEND_RIGHT, escape_mathtext, new_figure


def correlogram_figure(acf, pacf, *, title: str = ""):
    """ACF and PACF stems with their confidence bands (paper Figs. 3 and 4)."""
    fig, axes = new_figure(1, 2, figsize=(9.0, 3.2))
    for ax, c, name in ((axes[0], acf, "ACF"), (axes[1], pacf, "PACF")):
        lags = np.asarray(c.lags)[1:]
        ax.vlines(lags, 0.0, np.asarray(c.values)[1:], color=COLORS["model"])
        ax.plot(lags, np.asarray(c.values)[1:], "o", ms=3, color=COLORS["model"])
        ax.fill_between(lags, -np.asarray(c.band)[1:], np.asarray(c.band)[1:],
                        color=COLORS["band"], alpha=0.15, lw=0,
                        label=f"{100 * (1 - c.alpha):.0f} % band")
        ax.axhline(0.0, color="k", lw=0.6)
        ax.set_xlabel("lag")
        ax.set_title(escape_mathtext(f"{name} {title}".strip()))
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.2), borderaxespad=0.0)
    return fig


def prediction_figure(time, x, prediction, denoised, *, unit: str = "", max_points: int = 3000,
                      title: str = ""):
    """Data, one-step prediction, smoothed signal and removed noise (paper Fig. 5)."""
    time, x = np.asarray(time), np.asarray(x)
    sl = slice(0, min(time.size, max_points))  # a readable window, not 10^5 points
    fig, axes = new_figure(2, 1, figsize=(8.0, 5.0), sharex=True)
    t0 = time[sl] - time[0]
    axes[0].plot(t0, x[sl], color=COLORS["data"], lw=0.6, label="detrended data")
    axes[0].plot(t0, np.asarray(prediction.prediction)[sl], color=COLORS["model"], lw=0.8,
                 label="one-step prediction")
    axes[0].plot(t0, np.asarray(denoised.smoothed)[sl], color=COLORS["after"], lw=1.0,
                 label="Kalman-smoothed signal")
    axes[0].set_ylabel(unit)
    axes[0].legend(**LEGEND_RIGHT)
    axes[0].set_title(escape_mathtext(title or "ARMA one-step prediction and filtering"))
    axes[1].plot(t0, np.asarray(denoised.noise)[sl], color=COLORS["data"], lw=0.6,
                 label="removed noise (data - smoothed)")
    axes[1].set_xlabel("time from start (s)")
    axes[1].set_ylabel(unit)
    axes[1].legend(**LEGEND_RIGHT)
    return fig


def analysis_figure(analysis):
    """One page for the CLI: correlograms on top, prediction/filtering below."""
    import matplotlib.pyplot as plt

    from .style import STYLE

    doc = analysis.document
    with plt.rc_context(STYLE):
        fig = plt.figure(figsize=(9.0, 7.5), layout="constrained")
        top, bottom = fig.subfigures(2, 1, height_ratios=[1.0, 1.6])
        a1, a2 = top.subplots(1, 2)
        for ax, c, name in ((a1, analysis.acf, "ACF"), (a2, analysis.pacf, "PACF")):
            lags = np.asarray(c.lags)[1:]
            ax.vlines(lags, 0.0, np.asarray(c.values)[1:], color=COLORS["model"])
            ax.fill_between(lags, -np.asarray(c.band)[1:], np.asarray(c.band)[1:],
                            color=COLORS["band"], alpha=0.15, lw=0)
            ax.axhline(0.0, color="k", lw=0.6)
            ax.set_title(f"{name} of the detrended series")
            ax.set_xlabel("lag [samples]")
            ax.set_ylabel("partial autocorrelation" if name == "PACF" else "autocorrelation")
        b1, b2 = bottom.subplots(2, 1, sharex=True)
        n = min(analysis.x.size, 1000)
        t0 = analysis.time[:n] - analysis.time[0]
        b1.plot(t0, analysis.x[:n], color=COLORS["data"], lw=0.6, label="detrended data")
        b1.plot(t0, analysis.prediction.prediction[:n], color=COLORS["model"], lw=0.8,
                label="one-step prediction")
        b1.plot(t0, analysis.denoised.smoothed[:n], color=COLORS["after"], lw=1.0,
                label="smoothed signal")
        w = doc["whiteness"]
        b1.set_title(f"selected {doc['selected']} ({doc['criterion'].upper()}); Ljung-Box "
                     f"p = {w['ljung_box_p']:.3g}, rho_a2 = {w['rho_a2']:.3g}, "
                     f"rho_ax3 = {w['rho_ax3']:.3g}")
        b1.set_ylabel(f"rate [{doc['unit']}]")
        b1.legend(**LEGEND_RIGHT)
        b2.plot(t0, analysis.denoised.noise[:n], color=COLORS["data"], lw=0.6,
                label="removed noise")
        b2.set_ylabel(f"removed noise [{doc['unit']}]")
        b2.set_xlabel("time from start (s)")
        b2.legend(**LEGEND_RIGHT)
    return fig
