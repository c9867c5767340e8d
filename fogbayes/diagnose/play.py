"""The play operator, defined in :mod:`fogbayes.effects.play` (re-exported here)."""

from ..effects.play import play

__all__ = ["play"]
