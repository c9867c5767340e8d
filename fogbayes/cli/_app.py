"""The typer application every subcommand module registers on."""

import typer

app = typer.Typer(
    name="fogbayes",
    help="Probabilistic modelling of fiber-optic-gyroscope errors.\n\n"
    "Exit codes: 0 success, 1 the work failed (e.g. a fit did not converge and --strict), "
    "2 bad input (one line on stderr naming the file, column and row).",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)
