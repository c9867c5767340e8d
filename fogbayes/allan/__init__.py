"""The Allan noise family (paper 002, IEEE 952): the five-term model Q, N, B, K, R.

One package per model family; here every stage of this one (the model-free Allan
variance estimators themselves are in :mod:`fogbayes.stats`):

* :mod:`.model`    -- AVAR of each noise term as a pure function of tau;
* :mod:`.data`     -- the octave AVAR estimates the fits see, with their joint distribution;
* :mod:`.fit`      -- the paper's least squares and GLS, with intervals;
* :mod:`.bayes`    -- the NumPyro posterior (correlated estimates, datasheet priors);
* :mod:`.readout`  -- IEEE 952 slope readouts, for comparison;
* :mod:`.workflow` -- ``fit_recording`` (the command line's ``fogbayes allan``).

Nothing is imported here, so ``import fogbayes.allan.model`` does not start NumPyro.
"""
