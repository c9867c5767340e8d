"""Figures of the demonstration report: compensation and ADEV comparison."""

from __future__ import annotations

import numpy as np

from .style import COLORS, new_figure


def _block(x, time, window_s):
    k = max(1, int(round(window_s / np.median(np.diff(time)))))
    n = (len(x) // k) * k
    return time[:n].reshape(-1, k).mean(1), np.asarray(x)[:n].reshape(-1, k).mean(1)


def plot_compensation(rec, compensated: dict, oracle=None, *, window_s: float = 10.0):
    """Raw output and each compensated output as ``window_s`` block means against time."""
    fig, ax = new_figure(figsize=(7.5, 3.4))
    t, y = _block(rec.rate("deg/h"), rec.time, window_s)
    ax.plot(t / 3600, y, color=COLORS["data"], label="raw")
    for i, (name, c) in enumerate(compensated.items()):
        t, y = _block(c, rec.time, window_s)
        ax.plot(t / 3600, y, lw=1.0, label=f"compensated ({name})")
    if oracle is not None:
        t, y = _block(oracle, rec.time, window_s)
        ax.plot(t / 3600, y, color="k", lw=0.6, alpha=0.6, label="oracle (true model removed)")
    ax.set_xlabel("time [h]")
    ax.set_ylabel(f"output, {window_s:g} s means [deg/h]")
    ax.legend(ncol=2)
    return fig


def plot_adev_compare(adevs: dict):
    """Overlapping ADEV of several series on one log-log plot, with confidence bars."""
    fig, ax = new_figure(figsize=(6.5, 4.2))
    for name, a in adevs.items():
        err = np.vstack([a.dev - a.dev_low, a.dev_high - a.dev])
        ax.errorbar(a.tau, a.dev, yerr=err, marker="o", ms=3, capsize=2, label=name)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("tau [s]")
    ax.set_ylabel("Allan deviation [deg/h]")
    ax.legend()
    return fig
