"""The ``fogbayes`` command line: a thin layer over the library; each subcommand registers on :data:`app`.

``main`` turns a :class:`~fogbayes.errors.FogbayesError` or a usage error into one stderr line
(exit 2, no traceback); SIGTERM becomes ``SystemExit(143)`` and SIGINT ``SystemExit(130)``
(``fogbayes: interrupted``), so the writers of :mod:`fogbayes.data.atomic` leave the old output or none.
"""

from __future__ import annotations

import errno
import signal
import sys
import threading

import typer

from typer import Abort as _Abort

try:  # typer >= 0.23 carries its own click
    from typer._click.exceptions import ClickException as _ClickException
    from typer._click.exceptions import NoArgsIsHelpError as _NoArgsIsHelp
    from typer._click.exceptions import UsageError as _UsageError
    from typer._click.utils import PacifyFlushWrapper as _PacifyFlushWrapper
except ImportError:  # pragma: no cover - typer on the click package
    from click.exceptions import ClickException as _ClickException
    from click.exceptions import NoArgsIsHelpError as _NoArgsIsHelp
    from click.exceptions import UsageError as _UsageError
    from click.utils import PacifyFlushWrapper as _PacifyFlushWrapper

from ..data.atomic import Stopped, clear_stop, remove_orphans, watch_signals
from ..errors import FogbayesError
from . import _common
from ._app import app


@app.callback()
def _root(quiet: bool = typer.Option(False, "--quiet", "-q",
                                   help="No progress bars or status lines on stderr; results only.")):
    """Probabilistic modelling of fiber-optic-gyroscope errors."""
    _common.QUIET["on"] = quiet


# Subcommands register themselves on import (order = order in --help).
from . import allan, arma, batch, compensate, demo, export, fit, info, loop, plan, plan_chamber, pool, prior, report, simulate  # noqa: E402,F401

_common.add_reading_options(app)  # every reader has every reading option
_common.no_typer_path_checks(app)  # an unreadable input: one line, not click's usage box


class Terminated(SystemExit):
    """Raised by the SIGTERM handler: the command unwinds and exits with 128 + 15 = 143."""


def _terminated(signum, frame):
    """SIGTERM: unwind like an exception (cleanup and ``finally`` blocks run), exit 143.

    The flag comes first: should the exception land in a finaliser, where Python drops it,
    the next atomic write still stops before its rename (:func:`fogbayes.data.atomic.request_stop`).
    """
    from ..data.atomic import request_stop

    request_stop(128 + signum)
    raise Terminated(128 + signum)


class Interrupted(SystemExit):
    """Raised by the SIGINT (Ctrl-C) handler: the command unwinds and exits with 128 + 2 = 130.

    A ``SystemExit`` rather than ``KeyboardInterrupt`` so that click does not turn it into its
    own "Aborted!" block: the user reads one line, ``fogbayes: interrupted``.
    """


def _interrupted(signum, frame):
    """SIGINT: unwind like SIGTERM (cleanup and ``finally`` blocks run), exit 130."""
    from ..data.atomic import request_stop

    request_stop(128 + signum)
    raise Interrupted(128 + signum)


def _usage_line(exc) -> str:
    """A click usage error (missing option, no such command, invalid value) in one line:
    the command, what is wrong and where the options are listed."""
    where = exc.ctx.command_path if exc.ctx is not None else "fogbayes"
    msg = " ".join(exc.format_message().split()).rstrip(".")
    end = "" if msg.endswith("?") else "."  # "Did you mean 'fit'?"
    return f"{where}: {msg}{end} Fix: see '{where} --help'"


def _show_help(exc) -> None:
    try:
        from typer import rich_utils

        rich_utils.rich_format_error(exc)
    except ImportError:  # typer without rich
        exc.show()


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``fogbayes`` script; returns the exit code."""
    installed, previous, previous_int, unwatch = False, None, None, None
    if threading.current_thread() is threading.main_thread():
        previous, installed = signal.signal(signal.SIGTERM, _terminated), True
        previous_int = signal.signal(signal.SIGINT, _interrupted)
        unwatch = watch_signals()  # a stop is seen before a rename even if the handler waits
    try:
        # not standalone: a usage error is ours to print, in one line (_usage_line)
        code = app(args=argv, prog_name="fogbayes", standalone_mode=False)
        return code if isinstance(code, int) else 0
    except _NoArgsIsHelp as exc:  # 'fogbayes' alone: the help, as click shows it
        _show_help(exc)
        return exc.exit_code
    except _UsageError as exc:
        print(f"fogbayes: error: {_usage_line(exc)}", file=sys.stderr)
        return exc.exit_code
    except _ClickException as exc:
        print(f"fogbayes: error: {' '.join(exc.format_message().split())}", file=sys.stderr)
        return exc.exit_code
    except _Abort:  # end of input where the command read some
        print("fogbayes: aborted", file=sys.stderr)
        return 1
    except FogbayesError as exc:
        print(f"fogbayes: error: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:  # a path the user named cannot be read or written
        if exc.errno == errno.EPIPE:  # the reader of stdout went away (| head): quietly
            sys.stdout = _PacifyFlushWrapper(sys.stdout)
            sys.stderr = _PacifyFlushWrapper(sys.stderr)
            return 1
        from ..data.atomic import final_path  # the user's name, not the .tmp- one

        where = f"{final_path(exc.filename)}: " if exc.filename else ""
        print(f"fogbayes: error: {where}{exc.strerror or exc}. Fix: check the path and its "
              "folder's permissions", file=sys.stderr)
        return 2
    except Interrupted as exc:
        print("fogbayes: interrupted; unfinished outputs were not written", file=sys.stderr)
        return exc.code
    except SystemExit as exc:
        if isinstance(exc, Stopped) and exc.code == 130:  # Ctrl-C while a file was written
            print("fogbayes: interrupted; unfinished outputs were not written", file=sys.stderr)
        elif isinstance(exc, (Terminated, Stopped)):
            print("fogbayes: terminated (SIGTERM); unfinished outputs were not written",
                  file=sys.stderr)
        return exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
    finally:
        remove_orphans()  # temporaries whose writer never got to clean up (a signal)
        if unwatch is not None:
            unwatch()
        clear_stop()
        if installed:
            signal.signal(signal.SIGTERM, signal.SIG_DFL if previous is None else previous)
            signal.signal(signal.SIGINT,
                          signal.default_int_handler if previous_int is None else previous_int)
    return 0


def run() -> None:
    """The ``fogbayes`` script and ``python -m fogbayes``: :func:`main`, then the process ends
    as a normal exit ends it -- non-daemon threads joined, exit handlers run, the standard
    streams flushed -- but without the interpreter's teardown of every module and object
    (JAX's, Numba's, SciPy's), which took 0.4-0.6 s after a command that ran a compiled
    program (benchmarks/RESULTS_interactive.md). A caller of :func:`main` keeps the normal
    exit; an unexpected exception propagates as usual."""
    _end_process(main())


def _end_process(code: int) -> None:
    import atexit
    import os

    shutdown = getattr(threading, "_shutdown", None)  # CPython's first steps at exit
    exit_handlers = getattr(atexit, "_run_exitfuncs", None)
    if shutdown is None or exit_handlers is None:
        sys.exit(code)
    shutdown()
    exit_handlers()
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):  # a closed stream or a reader gone: nothing to add
            pass
    os._exit(code)


if __name__ == "__main__":
    run()
