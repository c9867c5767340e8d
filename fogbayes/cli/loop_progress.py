"""The progress line of ``fogbayes loop``: the step, the stage and the candidate tried.

Drawn on stderr (:data:`fogbayes.cli._common.console`) only when it is a terminal and not
``--quiet`` (:func:`fogbayes.cli._common.shows_progress`), from the stages the loop reports
(:mod:`fogbayes.loop.progress`). Steps are counted out of ``--max-steps``, an upper bound: the
loop stops when no candidate is supported, which only the data decide, so no time left
is shown -- the elapsed time is.
"""

from __future__ import annotations

from contextlib import contextmanager

from ..loop.progress import Stage, listening
from . import _common


def describe(title: str, stage: Stage) -> str:
    """``title, step 2 of <=5: refitting temperature_rate (2 of 3)``: the step, out of
    ``max_steps`` at most, the stage, and the candidate's place among those refitted."""
    if stage.step is None:
        where = "finishing"
    elif stage.step == 0:
        where = "base model"
    else:
        where = f"step {stage.step} of <={stage.max_steps}"
    which = (f" ({stage.index} of {stage.total})"
             if stage.index is not None and stage.total else "")
    return f"{title}, {where}: {stage.what}{which}"


@contextmanager
def loop_progress(title: str, max_steps: int):
    """Show the loop's stages under ``title`` while the block runs (nothing when
    :func:`~fogbayes.cli._common.shows_progress` is false)."""
    if not _common.shows_progress():
        yield
        return
    from rich.progress import Progress, SpinnerColumn, TextColumn, TimeElapsedColumn

    cols = [SpinnerColumn(), TextColumn("{task.description}"), TimeElapsedColumn()]
    with Progress(*cols, console=_common.console, transient=True) as bar:
        task = bar.add_task(title, total=None)

        def show(stage: Stage) -> None:
            bar.update(task, description=describe(title, stage), refresh=True)  # each stage seen

        with listening(show):
            yield
