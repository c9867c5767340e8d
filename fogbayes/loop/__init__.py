"""The closed loop: fit -> diagnose -> add the effect the evidence supports -> refit.

``run_loop(rec, model)`` returns a :class:`LoopResult` (typed steps, before/after metrics,
``to_json()`` with the docs/DESIGN.md contract, compensated columns).
"""

from .core import RULE, run_loop
from .result import LoopResult, Rejected, Step

__all__ = ["LoopResult", "RULE", "Rejected", "Step", "run_loop"]
