"""Time plots of a Recording: output and temperature channels."""

from __future__ import annotations

import numpy as np

from ..data import Recording
from .style import COLORS, new_figure


def plot_recording(rec: Recording, *, unit: str | None = None, outliers: np.ndarray | None = None,
                   max_points: int = 20_000):
    """Output (top) and temperatures (bottom) against time in hours.

    Long records are thinned to ``max_points`` for drawing only (every k-th sample).
    """
    unit = unit or rec.unit
    y = rec.output if unit == rec.unit else rec.rate(unit)
    k = max(1, rec.n // max_points)
    th = rec.time / 3600.0
    rows = 2 if rec.has_temperature else 1
    fig, axes = new_figure(rows, 1, sharex=True, figsize=(7.5, 2.6 * rows))
    axes = np.atleast_1d(axes)
    axes[0].plot(th[::k], y[::k], color=COLORS["data"], lw=0.6)
    if outliers is not None and outliers.any():
        axes[0].plot(th[outliers], y[outliers], "x", color=COLORS["model"], ms=4,
                     label=f"{int(outliers.sum())} outliers flagged")
        axes[0].legend()
    axes[0].set_ylabel(f"output [{unit}]")
    axes[0].set_title(f"{rec.meta.sensor_id}: {rec.n} samples at {rec.sample_rate:.4g} Hz")
    if rec.has_temperature:
        for j, name in enumerate(rec.temperature_names):
            axes[1].plot(th[::k], rec.temperatures[::k, j], lw=1.0, label=name)
        axes[1].set_ylabel("temperature [°C]")
        axes[1].legend()
    axes[-1].set_xlabel("time [h]")
    return fig
