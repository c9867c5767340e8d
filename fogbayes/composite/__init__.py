"""The composite family (paper 000): U = S1(T) S2(W) W + U0(T) + U1(T) t.

One package per model family; here every stage of this one:

* :mod:`.model`     -- parameters, scaled bases, orders grammar, prediction;
* :mod:`.cells`     -- the rate table's (T_i, W_j) cells and the operating time;
* :mod:`.noise`     -- white + AR(1)-across-cells noise of the cell means;
* :mod:`.fit`, :mod:`.classify`, :mod:`.compare` -- least squares (joint/product), the
  paper's classification fit, and order selection (RMS criterion, WAIC/LOO);
* :mod:`.bayes`     -- the NumPyro posterior;
* :mod:`.compensate` (and its compiled CPU loop :mod:`.compensate_loop`) -- the one
  inversion of the model for the input rate W, used by fits and by the closed loop's
  composite calibrations;
* :mod:`.tables`    -- paper 000's tables and before/after;
* :mod:`.workflow`  -- ``fit_recording`` / ``compensate_recording`` (the command line's).

Nothing is imported here, so ``import fogbayes.composite.cells`` does not start JAX.
"""
