"""Physical description of an added term: the numbers a user reads in ``steps[].detail``.

Coefficients are fitted on centred/scaled columns; each term kind turns them back into
physical units (deg/h and the covariate's own unit) in its ``describe``
(:mod:`fogbayes.effects.kinds`).
"""

from __future__ import annotations

from ..effects.terms import describe

__all__ = ["describe"]
