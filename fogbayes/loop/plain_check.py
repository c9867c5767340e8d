"""Never worse than the plain fit: the loop's final model against ``fogbayes fit``'s terms.

Both are scored by the same time-blocked held-out folds under the final noise model
(:func:`fogbayes.loop.holdout.score`): lpd = sum_k log p(y_k | y_(-k)), nats. The plain fit
(the base model at ``fogbayes fit``'s default orders, coefficients by least squares, as a
user without the loop would run it) is the baseline. When the final model trails it by
more than :data:`PLAIN_TOLERANCE_NATS`, the loop's base was too lean for this record (a
cubic the held-out gate refused, or drift that a third temperature power happens to
follow), and the loop's compensation would be worse than not using the loop. The loop
then tries, in this order, and keeps the first that is not worse than the plain fit:

1. the *union*: the plain fit's base terms with the loop's added terms (GLS, noise refitted
   from the final model's);
2. the plain fit's base terms alone, by GLS.

If neither reaches the plain fit, the best-scoring of the three (final, union, plain GLS)
is kept and the warning stays. Every score is written to the document's ``holdout``.
"""

from __future__ import annotations

import numpy as np

from ..diagnose.context import Context
from ..diagnose.fitting import ModelFit, fit_terms
from ..thermal.workflow import DEFAULT_ORDERS
from . import holdout
from .bases import base_terms

#: nats of held-out log predictive density by which the final model may trail the plain
#: fit and still count as "not worse": two estimators of the same terms (GLS and least
#: squares) differ by 1e-6..1e-2 nats on a record where the loop adds nothing, a difference
#: no compensated output shows; 0.5 nats is a density ratio of 1.6 over the whole record.
PLAIN_TOLERANCE_NATS = 0.5


def plain_check(ctx: Context, model: str, fit: ModelFit, h_final, n_base: int):
    """Compare the final ``fit`` (its first ``n_base`` terms the loop's base) with the plain
    fit; returns (the fit to keep, its held-out score, the ``holdout`` fields)."""
    if model not in DEFAULT_ORDERS:
        return fit, h_final, {}
    terms = tuple(base_terms(ctx, model, DEFAULT_ORDERS[model]))
    plain = ModelFit(terms, ctx.block_design(list(terms)), fit.noise, np.zeros(0))
    h_plain = holdout.score(ctx, plain, ols=True)
    out = {"plain_fit": f"fogbayes fit -m {model} (orders {DEFAULT_ORDERS[model]}, "
                        "least squares)",
           "lpd_plain_fit": h_plain.lpd, "tolerance_nats": PLAIN_TOLERANCE_NATS}

    def not_worse(h) -> bool:
        return bool(h.lpd >= h_plain.lpd - PLAIN_TOLERANCE_NATS)

    if not_worse(h_final):
        return fit, h_final, {**out, "final_not_worse_than_plain_fit": True}
    tried = [("final", fit.terms, h_final)]
    added = fit.terms[n_base:]
    options = [("plain base with the loop's terms", terms + tuple(added))] if added else []
    options.append(("plain base by GLS", terms))
    for name, ts in options:
        X = ctx.block_design(list(ts))
        if np.linalg.matrix_rank(X[np.asarray(ctx.grid.mask) > 0]) < X.shape[1]:
            continue  # a loop term that repeats a plain-base column (an added cubic)
        # scored under the same noise as the plain fit and the final model: comparable
        h = holdout.score(ctx, ModelFit(ts, X, fit.noise, np.zeros(0)))
        tried.append((name, ts, h))
        if not_worse(h):
            break
    name, ts, h_best = tried[-1] if not_worse(tried[-1][2]) else max(
        tried, key=lambda x: x[2].lpd)
    out.update({"final_not_worse_than_plain_fit": not_worse(h_best),
                "lpd_loop_model": h_final.lpd,
                "replaced_by": None if name == "final" else name,
                "tried": {n: h.lpd for n, _, h in tried}})
    if name == "final":
        return fit, h_final, out
    # the kept terms' own fit (noise re-estimated from the final model's) for the document
    kept = fit_terms(ctx, ts, spec=fit.noise.spec, theta0=fit.noise.theta)
    return kept, h_best, out
