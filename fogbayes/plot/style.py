"""One consistent, print-quality look for every fogbayes figure."""

from __future__ import annotations

STYLE = {
    "figure.figsize": (7.5, 3.6),
    "figure.dpi": 110,
    "axes.grid": True,
    "grid.alpha": 0.3,
    "axes.spines.top": False,
    "axes.spines.right": False,
    "axes.titlesize": 11,
    "axes.labelsize": 10,
    "legend.fontsize": 8.5,
    "legend.frameon": False,
    "lines.linewidth": 1.2,
}
COLORS = {"data": "#7f8c99", "model": "#c0392b", "after": "#2b5d8a", "band": "#2b5d8a", "temp": "#d35400"}


def new_figure(nrows: int = 1, ncols: int = 1, **kw):
    """``plt.subplots`` under the fogbayes style (works headless: Agg when no display)."""
    import matplotlib

    if matplotlib.get_backend().lower() not in ("agg", "module://matplotlib_inline.backend_inline"):
        import os

        if not os.environ.get("DISPLAY"):
            matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    with plt.rc_context(STYLE):
        fig, ax = plt.subplots(nrows, ncols, layout="constrained", **kw)
    return fig, ax
