"""Subcommands of DESIGN.md that are not built yet: each says so and exits with code 1."""

from __future__ import annotations

import typer

from ._app import app

_NOT_BUILT = {
    "batch": "fleet processing of many recordings",
}


def _make(name: str, what: str):
    def command(args: list[str] = typer.Argument(None, hidden=True)):
        typer.echo(f"fogbayes {name}: {what} is not built yet in this version.", err=True)
        raise typer.Exit(1)

    command.__doc__ = f"[not built yet] {what[0].upper()}{what[1:]}."
    return command


for _name, _what in _NOT_BUILT.items():
    app.command(name=_name, context_settings={"allow_extra_args": True,
                                              "ignore_unknown_options": True})(_make(_name, _what))
