"""The composite family (paper 000): U = S1(T) S2(W) W + U0(T) + U1(T) t.

Here: the rate-table cells (:mod:`.cells`), the paper's tables (:mod:`.tables`) and the one
inversion of the model for the input rate W (:mod:`.compensate`, with its compiled CPU loop
:mod:`.compensate_loop`), used by fits and by the closed loop's composite calibrations.
The model's parameters live in :mod:`fogbayes.models.composite`, its fits in
:mod:`fogbayes.inference` (``composite_*``) and its workflow in
:mod:`fogbayes.workflow.composite`.

Nothing is imported here, so ``import fogbayes.composite.cells`` does not start JAX.
"""
