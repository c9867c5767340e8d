"""The library of candidate effects: each registered effect (:mod:`fogbayes.effects`) as terms.

Each candidate is a family of :class:`~fogbayes.effects.terms.Term` s, one per value of its
searched parameter, added to the current model (nested, so a likelihood ratio compares them).
Grids are coarse; :mod:`fogbayes.loop.refine` refines the value. ``markov_noise`` belongs
to the noise model (:mod:`fogbayes.loop.noise_model`).
"""

from __future__ import annotations

from ..effects import REGISTRY, Candidate

#: every effect name, in docs/DESIGN.md order
EFFECTS = tuple(REGISTRY)

#: How many times the loop may add an effect of each name (the others: once).
MAX_TIMES = {n: e.max_times for n, e in REGISTRY.items() if e.max_times > 1}


def candidates_for(ctx, terms, *, effects: tuple[str, ...] | None = None) -> list[Candidate]:
    """Every deterministic candidate the current model (``terms``) lacks: the linear ones in
    registry order, then the spectral ones."""
    out = [c for name, eff in REGISTRY.items() if effects is None or name in effects
           for c in eff.candidates(ctx, terms)]
    return [c for c in out if c.kind == "linear"] + [c for c in out if c.kind != "linear"]


__all__ = ["EFFECTS", "MAX_TIMES", "Candidate", "candidates_for"]
