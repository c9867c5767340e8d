"""The ARMA drift family (paper 002, section 2): ARMA(p, q) models of the gyro drift.

:mod:`.model`, :mod:`.fit` (Hannan-Rissanen, exact MLE), :mod:`.select` (AIC/BIC),
:mod:`.bayes`, :mod:`.filter` (prediction, denoising), :mod:`.workflow` (``fogbayes arma``).
Nothing is imported here.
"""
