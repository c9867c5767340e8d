"""The first-order lag filter, defined in :mod:`fogbayes.effects.lag` (re-exported here)."""

from ..effects.lag import first_order_lag

__all__ = ["first_order_lag"]
