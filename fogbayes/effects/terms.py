"""Model terms: every column a base model, candidate, calibration or simulated effect uses.

A :class:`Term` is data (``kind`` + ``params``); its meaning is the
:class:`~fogbayes.effects.kinds.Kind` registered under ``kind``. :func:`columns` evaluates it on
:class:`~fogbayes.preprocess.covariates.Covariates` at samples or blocks.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np

from .kinds import KINDS, kind_of
from .lag import first_order_lag  # noqa: F401 -- re-exported (the loop's lag filter)

__all__ = ["KINDS", "Term", "chunk_columns", "columns", "describe", "design", "labels"]


class Term(NamedTuple):
    """One model term: ``kind`` (see :mod:`fogbayes.effects.kinds`) and its parameters."""

    kind: str
    params: dict[str, Any]

    @property
    def n_cols(self) -> int:
        return kind_of(self.kind).n_cols(self.params)

    @property
    def applies(self) -> str:
        """``"sensor"`` (carried to a new run) or ``"run"`` (an event of this run)."""
        return kind_of(self.kind).applies


def columns(term: Term, cov) -> np.ndarray:
    """Evaluate ``term`` on ``cov`` -> (n, term.n_cols)."""
    return kind_of(term.kind).columns(term.params, cov)


def design(terms: list[Term], cov) -> np.ndarray:
    """Columns of every term side by side (n, sum of n_cols)."""
    return np.column_stack([columns(tm, cov) for tm in terms])


def chunk_columns(terms: list[Term], cov, states: list | None) -> tuple[list, list]:
    """Each term's columns on one chunk of a record read in order, and the states the next
    chunk needs (``states`` None on the first chunk): pieces of :func:`columns` of the
    whole record (:meth:`~fogbayes.effects.kinds.Kind.chunk_columns`)."""
    states = [None] * len(terms) if states is None else states
    out = [kind_of(tm.kind).chunk_columns(tm.params, cov, st) for tm, st in zip(terms, states)]
    return [c for c, _ in out], [st for _, st in out]


def labels(term: Term) -> list[str]:
    """Readable names of a term's columns."""
    return kind_of(term.kind).labels(term.params)


def describe(term: Term, beta, se, *, t0: float = 0.0) -> dict[str, Any]:
    """Physical reading of a term's fitted coefficients (``{"term": kind, ...}``)."""
    return {"term": term.kind, **kind_of(term.kind).describe(term.params, np.asarray(beta),
                                                              np.asarray(se), t0)}
