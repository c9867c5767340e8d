"""The ARMA drift family (paper 002, section 2): ARMA(p, q) models of the gyro drift.

One package per model family; here every stage of this one:

* :mod:`.model`    -- exact Gaussian likelihood, stationary/invertible parameterisation;
* :mod:`.fit`      -- Hannan-Rissanen start, exact maximum likelihood (optax);
* :mod:`.select`   -- order selection by AIC/BIC over the candidates, in one compiled call;
* :mod:`.bayes`    -- the NumPyro posterior and WAIC/LOO order comparison;
* :mod:`.filter`   -- one-step prediction, residuals, Kalman denoising;
* :mod:`.workflow` -- ``analyse_recording`` (the command line's ``fogbayes arma``).

Nothing is imported here.
"""
