"""Time plots of a Recording: output and temperature channels."""

from __future__ import annotations

import numpy as np

from ..data import Recording
from .style import COLORS, LEGEND_RIGHT, escape_mathtext, new_figure


def plot_recording(rec: Recording, *, unit: str | None = None, outliers: np.ndarray | None = None,
                   gross: np.ndarray | None = None, max_points: int = 20_000):
    """Output (top) and temperatures (bottom) against time in hours.

    Long records are thinned to ``max_points`` for drawing only (every k-th sample); 10 s
    means are drawn over the samples when the record is sampled faster than that.
    Outliers are drawn in proportion: ``gross`` samples (gross errors) as red crosses,
    the other ``outliers`` (n-sigma flags that are the noise's own tail) as small dots.
    Without ``gross``, flags are all emphasised only when they are few (at most 0.5 % of
    the samples and 50); more look like a Gaussian tail and are drawn small.
    """
    unit = unit or rec.unit
    y = rec.output if unit == rec.unit else rec.rate(unit)
    k = max(1, rec.n // max_points)
    th = rec.time / 3600.0
    rows = 2 if rec.has_temperature else 1
    fig, axes = new_figure(rows, 1, sharex=True, figsize=(9.0, 2.6 * rows))
    axes = np.atleast_1d(axes)
    axes[0].plot(th[::k], y[::k], color=COLORS["data"], lw=0.6, alpha=0.8, label="samples")
    dt = float(np.median(np.diff(rec.time))) if rec.n > 1 else 1.0
    if rec.n > 1 and dt < 5.0:
        m = max(1, int(round(10.0 / dt)))
        nn = (rec.n // m) * m
        if nn >= 2 * m:
            axes[0].plot(th[:nn].reshape(-1, m).mean(1), y[:nn].reshape(-1, m).mean(1),
                         color="#2c3e50", lw=0.9, label="10 s means")
    if outliers is not None and outliers.any():
        outliers = np.asarray(outliers, bool)
        if gross is None:
            few = outliers.sum() <= min(50, 0.005 * rec.n)
            gross = outliers if few else np.zeros_like(outliers)
        gross = np.asarray(gross, bool) & outliers
        tail = outliers & ~gross
        if tail.any():
            axes[0].plot(th[tail], y[tail], ".", color="#b07a7a", ms=1.5, alpha=0.6,
                         label=f"{int(tail.sum())} flagged (noise tail)")
        if gross.any():
            axes[0].plot(th[gross], y[gross], "x", color=COLORS["model"], ms=5, mew=1.2,
                         label=f"{int(gross.sum())} gross errors")
    axes[0].legend(**LEGEND_RIGHT)
    axes[0].set_ylabel(escape_mathtext(f"output [{unit}]"))
    axes[0].set_title(escape_mathtext(f"{rec.meta.sensor_id}: {rec.n} samples at "
                                      f"{rec.sample_rate:.4g} Hz"))
    if rec.has_temperature:
        for j, name in enumerate(rec.temperature_names):
            axes[1].plot(th[::k], rec.temperatures[::k, j], lw=1.0, label=escape_mathtext(name))
        axes[1].set_ylabel("temperature [°C]")
        axes[1].legend(**LEGEND_RIGHT)
    axes[-1].set_xlabel("time [h]")
    return fig
