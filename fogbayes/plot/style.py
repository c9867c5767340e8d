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

# One colour per model (and per reference series), the same in every figure of a report.
MODEL_COLORS = {
    "raw": "#7f8c99",         # uncompensated output: the data grey
    "bias-t": "#e08214",      # orange
    "thermal": "#2b5d8a",     # blue
    "composite": "#1b9e77",   # green
    "allan": "#7570b3",       # purple
    "oracle": "#111111",      # the true deterministic error removed (simulations)
    "loop": "#c0392b",        # the closed loop's final model: red
}
_EXTRA = ("#8c510a", "#01665e", "#762a83", "#b2182b", "#4d4d4d")


def model_color(name: str) -> str:
    """The colour of model ``name`` (``'thermal'``, ``'bias-t'``, ``'raw'``, ...) in every figure.

    Unknown names get a fixed colour from their spelling, so they too stay the same.
    """
    key = str(name).split(" ")[0].lower()
    if key in MODEL_COLORS:
        return MODEL_COLORS[key]
    return _EXTRA[sum(map(ord, key)) % len(_EXTRA)]


# Legends outside the data: to the right of the axes (use with ax.legend(**LEGEND_RIGHT)).
LEGEND_RIGHT = {"loc": "upper left", "bbox_to_anchor": (1.01, 1.0), "borderaxespad": 0.0}


def escape_mathtext(s) -> str:
    """User text (sensor ids, column and file names) as literal text in a matplotlib title
    or label: ``$`` would start mathtext, and ``$\\alpha^{$`` would crash the figure."""
    return str(s).replace("$", r"\$")


def figure_format(path, flag: str = "--plot") -> str:
    """The figure format of ``path`` from its extension, checked before any work is done.

    Raises :class:`~fogbayes.errors.ArgumentError` naming ``flag`` and the supported
    extensions when matplotlib cannot write it (no extension: PNG).
    """
    from pathlib import Path

    from matplotlib.backend_bases import FigureCanvasBase

    from ..errors import ArgumentError

    ext = Path(path).suffix.lower().lstrip(".")
    supported = sorted(FigureCanvasBase.get_supported_filetypes())
    if ext and ext not in supported:
        raise ArgumentError(f"cannot write a figure as '.{ext}' ({path})", column=flag,
                            fix=f"use one of {', '.join('.' + e for e in supported)}")
    return ext or "png"


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
