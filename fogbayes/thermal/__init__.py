"""The thermal family (paper 004): bias = polynomial in T (+ dT/dt, + T dT/dt) + noise.

One package per model family; here every stage of this one (``bias-t`` is its
temperature-only member):

* :mod:`.model`      -- the model's specification, covariates and scaled basis;
* :mod:`.data`       -- processing: segments, outlier flags, blocks, per-sample covariates;
* :mod:`.workflow`   -- ``fit_recording`` / ``compensate_recording`` (the command line's),
  order selection by the RMS criterion, validity range, the fit document;
* :mod:`.bayes`      -- the NumPyro posterior and WAIC/LOO order comparison;
* :mod:`.compensate` (and its compiled CPU loop :mod:`.compensate_loops`) -- the one
  compensator ``y - X(z) b`` of the family, also used by batch, stream and export;
* :mod:`.pan_tvac`   -- the PAN thermal-vacuum recipe (file layout and options).

Nothing is imported here, so ``import fogbayes.thermal.model`` does not start JAX.
"""
