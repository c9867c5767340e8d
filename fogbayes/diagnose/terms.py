"""Model terms, defined in :mod:`fogbayes.effects.terms` (re-exported here)."""

from ..effects.terms import (KINDS, Term, chunk_columns, columns, describe, design,
                             first_order_lag, kind_of, labels)

__all__ = ["KINDS", "Term", "chunk_columns", "columns", "describe", "design",
           "first_order_lag", "kind_of", "labels"]
