"""The closed loop: fit -> diagnose -> add the effect the evidence supports -> refit.

``run_loop(rec, model)`` returns a :class:`LoopResult` (typed steps, before/after metrics,
``to_json()`` with the docs/DESIGN.md contract, compensated columns). The diagnosis, residuals
-> findings: :mod:`.candidates`, :mod:`.evidence`, :mod:`.reml`, :mod:`.compete`,
:mod:`.markov`, :mod:`.elpd`, :mod:`.scans`, :mod:`.refine`, :mod:`.noise_prior`; covariates
and the block grid: :mod:`fogbayes.preprocess.covariates`.
"""

__all__ = ["LoopResult", "RULE", "Rejected", "Step", "run_loop"]

# Resolved on first use: importing a light submodule (``fogbayes.loop.progress``, which every
# CLI command imports) must not import the loop's machinery and JAX with it.
_LAZY = {"RULE": ".core", "run_loop": ".core", "LoopResult": ".result", "Rejected": ".result",
         "Step": ".result"}


def __getattr__(name: str):
    if name in _LAZY:
        import importlib

        value = getattr(importlib.import_module(_LAZY[name], __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'fogbayes.loop' has no attribute {name!r}")
