"""The thermal family (paper 004): bias = polynomial in T (+ dT/dt, + T dT/dt) + noise.

:mod:`.model`, :mod:`.data`, :mod:`.workflow` (fit, compensate, orders, document),
:mod:`.bayes`, :mod:`.compensate` / :mod:`.compensate_loops` (the one compensator ``y - X(z) b``),
:mod:`.pan_tvac`. ``bias-t`` is the temperature-only member. Nothing is imported here.
"""
