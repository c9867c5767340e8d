"""Figures (matplotlib) for notebooks and reports; every function returns a Figure.

Import the submodules directly (``fogbayes.plot.recording``, ``fogbayes.plot.allan``,
...); matplotlib is imported lazily so that ``import fogbayes`` stays light.
"""
