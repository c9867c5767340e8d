"""The ``fogbayes`` command line: a thin layer over the library.

Every subcommand lives in its own module and registers itself on :data:`app`. ``main``
turns a :class:`~fogbayes.errors.FogbayesError` (bad input) into one line on stderr and
exit code 2, never a traceback.
"""

from __future__ import annotations

import sys

import typer

from ..errors import FogbayesError
from . import _common
from ._app import app


@app.callback()
def _root(quiet: bool = typer.Option(False, "--quiet", "-q",
                                   help="No progress bars or status lines on stderr; results only.")):
    """Probabilistic modelling of fiber-optic-gyroscope errors."""
    _common.QUIET["on"] = quiet


# Subcommands register themselves on import (order = order in --help).
from . import allan, arma, batch, compensate, demo, fit, info, loop, report, simulate  # noqa: E402,F401


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``fogbayes`` script; returns the exit code."""
    try:
        # standalone mode: click prints usage errors itself and exits with code 2.
        app(args=argv, prog_name="fogbayes", standalone_mode=True)
    except FogbayesError as exc:
        print(f"fogbayes: error: {exc}", file=sys.stderr)
        return 2
    except SystemExit as exc:
        return exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
