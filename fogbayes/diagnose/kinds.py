"""The term kinds, defined in :mod:`fogbayes.effects.kinds` (re-exported here)."""

from ..effects.kinds import DRIVER_LABELS, KINDS, Kind, kind_of

__all__ = ["DRIVER_LABELS", "KINDS", "Kind", "kind_of"]
