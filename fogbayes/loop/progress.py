"""Where the closed loop is: its step and the candidate it is trying, for a progress display.

:func:`fogbayes.loop.run_loop` calls :func:`tell` at each stage; a caller that wants to show
progress (the command line's bar) wraps the run in :func:`listening`. Without a listener
:func:`tell` does nothing. The loop's length depends on the data (it stops when no
candidate is supported), so a step count is an upper bound: ``max_steps``.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import NamedTuple


class Stage(NamedTuple):
    """One stage of the loop.

    step: 1-based step (0 before the first step, i.e. the base fit and noise model; None
    after the last); max_steps: the most steps the run may take; what: the stage in words
    ("screening 9 candidates", "refitting temperature_rate", ...); candidate: the effect
    being tried, if any; index, total: its place among the candidates refitted this step.
    """

    step: int | None
    max_steps: int
    what: str
    candidate: str | None = None
    index: int | None = None
    total: int | None = None


_LISTENER: dict = {"fn": None}


def tell(step: int | None, max_steps: int, what: str, candidate: str | None = None,
         index: int | None = None, total: int | None = None) -> None:
    """Pass a :class:`Stage` to the listener of :func:`listening`, if any."""
    fn = _LISTENER["fn"]
    if fn is not None:
        fn(Stage(step, max_steps, what, candidate, index, total))


@contextmanager
def listening(fn: Callable[[Stage], None]) -> Iterator[None]:
    """Call ``fn(stage)`` at each stage of the loops run inside the block."""
    before, _LISTENER["fn"] = _LISTENER["fn"], fn
    try:
        yield
    finally:
        _LISTENER["fn"] = before
