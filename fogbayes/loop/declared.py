"""Effects the user declares (``run_loop(..., declared=...)``, ``fogbayes loop --effect``).

A declared effect joins the base model before the search, as a loop step without a test. Its
searched parameter is chosen as the loop chooses a screened candidate's: among the effect's
candidates on the current model (:meth:`fogbayes.effects.Effect.candidates`), the grid value
with the smallest fixed-noise chi^2 p-value under the model's REML noise
(:func:`fogbayes.loop.evidence.screen`, candidates ranked by their calibrated p),
refined between its grid neighbours (:func:`~fogbayes.loop.refine.refine`), refitted by
GLS with the noise by maximum likelihood and polished
(:func:`~fogbayes.loop.refine.polish`). The step's evidence says ``declared`` and gives
2 (logL_with - logL_without) for the record; no level decides whether it stays.
"""

from __future__ import annotations

from typing import NamedTuple

from . import evidence as ev
from .context import Context
from .fitting import ModelFit, fit_terms
from .refine import polish, refine
from .reml import with_reml
from ..effects import REGISTRY, Effect
from ..errors import ArgumentError
from .bases import ALLOWED, allowed

DECLARED_RULE = ("declared by the user (--effect / declared=): added to the base model "
                 "without a test; its searched parameter chosen as for a screened candidate")


def declarable(model: str) -> tuple[str, ...]:
    """The effects a user may declare on ``model``: those the loop may add and searches
    (a noise component such as ``markov_noise`` is chosen by the loop, not declared)."""
    return tuple(n for n in allowed(model) if n in REGISTRY and not REGISTRY[n].stochastic
                 and type(REGISTRY[n]).candidates is not Effect.candidates)


def check_declared(names, model: str, *, where: str = "--effect") -> tuple[str, ...]:
    """``names`` as a tuple, each a declarable effect of ``model`` (one line naming ``where``,
    an option or an argument, and the known names otherwise)."""
    if isinstance(names, str) and names:
        raise ArgumentError("declared effects must be a list of names, not one string",
                            argument=where, fix=f"pass a tuple of names: declared=({names!r},)")
    names = tuple(names or ())
    if not names:
        return names
    if model not in ALLOWED:
        return names  # the base model's own check names the model
    known = declarable(model)
    for n in names:
        if n not in known:
            what = (f"unknown effect '{n}'" if n not in REGISTRY else
                    f"effect '{n}' cannot be declared on model {model} (the loop chooses it)")
            raise ArgumentError(what, argument=where, fix=f"use one of {', '.join(known)}")
    return names


class Declared(NamedTuple):
    screened: ev.Screened
    fit: ModelFit
    lr: float


def declare(ctx: Context, fit: ModelFit, name: str, *, n_sims: int, seed: int,
            cache: dict | None = None) -> Declared:
    """``fit`` with effect ``name`` added (module doc)."""
    cands = REGISTRY[name].candidates(ctx, list(fit.terms))
    screened = []
    if cands:
        wm, screened = ev.screen(ctx, with_reml(ctx, fit, cache), cands, n_sims=n_sims,
                                 seed=seed)
    if not screened:
        raise ArgumentError(f"effect '{name}' cannot be added to this model on this recording "
                            "(its driver does not vary, its columns are already in the model, "
                            "or it is there as often as it may be)", flag="--effect",
                            fix=f"drop --effect {name}")
    s = screened[0]
    term, _ = refine(ctx, wm, s)
    alt = fit_terms(ctx, fit.terms + (term,), spec=fit.noise.spec, theta0=fit.noise.theta)
    new = polish(ctx, fit, alt)
    return Declared(s, new, max(2.0 * (new.loglik - fit.loglik), 0.0))


def evidence_json(d: Declared) -> dict:
    """A declared step's ``evidence``: what the record says of it, no decision."""
    return {"declared": True, "rule": DECLARED_RULE, "likelihood_ratio": d.lr,
            "dof": d.screened.dof, "searched_value": d.screened.best_value}
