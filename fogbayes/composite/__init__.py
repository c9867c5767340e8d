"""The composite family (paper 000): U = S1(T) S2(W) W + U0(T) + U1(T) t.

:mod:`.model` (parameters, bases, orders, prediction), :mod:`.cells`, :mod:`.noise`,
:mod:`.fit` / :mod:`.classify` / :mod:`.compare` (fits and order selection), :mod:`.bayes`,
:mod:`.compensate` / :mod:`.compensate_loop` (the one inversion for W), :mod:`.tables`,
:mod:`.workflow`. Nothing is imported here (``fogbayes.composite.cells`` does not start JAX).
"""
