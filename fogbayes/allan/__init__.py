"""The Allan noise family (paper 002, IEEE 952): the five-term model Q, N, B, K, R.

:mod:`.model` (AVAR of each term), :mod:`.data` (octave estimates and their joint
distribution), :mod:`.fit` (least squares, GLS), :mod:`.bayes` (NumPyro), :mod:`.readout`
(IEEE 952 slopes), :mod:`.workflow` (``fogbayes allan``); estimators in :mod:`fogbayes.stats`.
Nothing is imported here (``fogbayes.allan.model`` does not start NumPyro).
"""
