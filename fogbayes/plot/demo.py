"""Figures of the demonstration report: compensation and ADEV comparison."""

from __future__ import annotations

import numpy as np

from .style import LEGEND_RIGHT, model_color, new_figure


def _block(x, time, window_s):
    k = max(1, int(round(window_s / np.median(np.diff(time)))))
    n = (len(x) // k) * k
    return time[:n].reshape(-1, k).mean(1), np.asarray(x)[:n].reshape(-1, k).mean(1)


def plot_compensation(rec, compensated: dict, oracle=None, *, window_s: float = 10.0):
    """Raw output and each compensated output as ``window_s`` block means against time.

    With ``oracle`` (the rate with the TRUE deterministic error removed, simulations only)
    a second panel shows ``compensated - oracle`` = the deterministic error each model
    leaves, against the oracle's zero line: the two would overprint in the first panel.
    """
    rows = 2 if oracle is not None else 1
    fig, axes = new_figure(rows, 1, sharex=True, figsize=(8.5, 2.9 * rows), squeeze=False)
    ax = axes[0, 0]
    t, y = _block(rec.rate("deg/h"), rec.time, window_s)
    ax.plot(t / 3600, y, color=model_color("raw"), lw=1.0, label="raw output")
    for name, c in compensated.items():
        t, y = _block(c, rec.time, window_s)
        ax.plot(t / 3600, y, lw=1.0, color=model_color(name), label=f"compensated, {name}")
    ax.set_ylabel(f"output, {window_s:g} s means\n[deg/h]")
    ax.legend(**LEGEND_RIGHT)
    if oracle is not None:
        ax2 = axes[1, 0]
        t, yo = _block(oracle, rec.time, window_s)
        ax2.axhline(0.0, color=model_color("oracle"), lw=0.8, ls="--",
                    label="oracle: true error removed")
        for name, c in compensated.items():
            t, y = _block(c, rec.time, window_s)
            ax2.plot(t / 3600, y - yo, lw=1.2, color=model_color(name), label=f"{name} - oracle")
        ax2.set_ylabel(f"error the model leaves,\n{window_s:g} s means [deg/h]")
        ax2.legend(**LEGEND_RIGHT)
    axes[-1, 0].set_xlabel("time [h]")
    return fig


def plot_adev_compare(adevs: dict):
    """Overlapping ADEV of several series on one log-log plot, with confidence bars."""
    fig, ax = new_figure(figsize=(8.0, 4.0))
    for name, a in adevs.items():
        err = np.vstack([a.dev - a.dev_low, a.dev_high - a.dev])
        raw = name == "raw"
        ax.errorbar(a.tau, a.dev, yerr=err, marker="s" if raw else "o", ms=4 if raw else 3,
                    mfc="none" if raw else None, ls="--" if raw else "-", capsize=2,
                    color=model_color(name), zorder=3 if raw else 2,
                    label="raw output" if raw else f"compensated, {name}")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("averaging time tau [s]")
    ax.set_ylabel("Allan deviation [deg/h]")
    ax.legend(**LEGEND_RIGHT)
    return fig
