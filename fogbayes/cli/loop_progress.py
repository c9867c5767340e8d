"""The progress line of ``fogbayes loop``: step (of at most ``--max-steps``), stage, candidate, elapsed time.

Drawn on stderr only on a terminal and without ``--quiet``
(:func:`fogbayes.cli._common.shows_progress`), from :mod:`fogbayes.loop.progress`.
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
