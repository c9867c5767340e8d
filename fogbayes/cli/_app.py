"""The typer application every subcommand module registers on."""

import typer

#: In typer's rich help a single newline is kept as a line break: prose paragraphs are
#: therefore one line each (rich wraps them), example lines are separate lines.
HELP = (
    "Probabilistic modelling of fiber-optic-gyroscope errors.\n\n"
    "Every command reads recordings (CSV, Parquet or NPZ with columns time, output, "
    "temperature, ...) and writes results to files. Status lines and progress bars go to "
    "stderr (none with -q/--quiet, given before or after the command name); '--json -' "
    "writes a command's JSON document to stdout and nothing else. "
    "'fogbayes COMMAND --help' shows a command's options and examples.\n\n"
    "Exit codes: 0 success; 1 the work failed (a fit that did not converge with --strict, "
    "a batch with a failed recording); 2 bad input: one line on stderr starting "
    "'fogbayes: error:' that names the file, column and row and how to fix it."
)

EPILOG = """Examples:
  fogbayes demo --out demo_out
  fogbayes simulate thermal --seed 1 --out run.csv
  fogbayes fit run.csv --model thermal --json fit.json
  fogbayes -q allan run.csv --json - > adev.json
Every command's --help ends with examples of its own."""

app = typer.Typer(
    name="fogbayes",
    help=HELP,
    epilog=EPILOG,
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)
