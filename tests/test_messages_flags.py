"""Every fix a message suggests is runnable: the flags it names exist.

Error messages end with 'Fix: ...', often naming a command-line flag. A flag that does
not exist (the old '--output-column', '--temperature-column') sends the user to a second
error. Two checks: every '--flag' written in a string anywhere in fogbayes' source is an
option of some fogbayes command (and of the command whose module writes it); and the
missing-column error of each command that reads a recording names a flag that the same
command then accepts, with which it succeeds.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest
import typer

import fogbayes
from fogbayes.cli import app, main
from fogbayes.simulate import simulate

PACKAGE = Path(fogbayes.__file__).resolve().parent
FLAG = re.compile(r"(?<![\w-])--[a-z][a-z0-9]*(?:-[a-z0-9]+)*")
#: Flags of other programs that fogbayes' text mentions (pip, pytest, chromium ...).
FOREIGN = {"--nbmake", "--force-reinstall", "--headless", "--no-sandbox", "--disable-gpu", "--screenshot",
           "--window-size", "--print-to-pdf", "--no-pdf-header-footer", "--enable-logging",
           "--v", "--virtual-time-budget", "--run-all-compositor-stages-before-draw",
           "--user-data-dir", "--no-first-run", "--disable-extensions", "--dump-dom",
           "--help"}


def _options() -> dict[str, set[str]]:
    group = typer.main.get_command(app)
    out = {name: {o for p in cmd.params for o in (*p.opts, *p.secondary_opts)}
           for name, cmd in group.commands.items()}
    out[""] = {o for p in group.params for o in p.opts}
    return out


def _string_flags(path: Path) -> set[str]:
    flags = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Constant) and isinstance(node.value, str):
            flags |= set(FLAG.findall(node.value))
    return flags


SOURCES = sorted(p for p in PACKAGE.rglob("*.py") if _string_flags(p) - FOREIGN)


@pytest.mark.parametrize("path", SOURCES, ids=[str(p.relative_to(PACKAGE)) for p in SOURCES])
def test_every_flag_in_the_source_exists(path):
    options = _options()
    known = set().union(*options.values())
    flags = _string_flags(path) - FOREIGN
    assert flags - known == set(), f"{path.name} names flags no command has"
    if path.parent.name == "cli" and path.stem in options:  # a command's own messages
        assert flags - options[path.stem] - options[""] - _mentions_other_commands(path) == set()


def _mentions_other_commands(path: Path) -> set[str]:
    """Flags of other commands that a command's help quotes ('fogbayes fit --json')."""
    text, options = path.read_text(encoding="utf-8"), _options()
    quoted = set()
    for cmd in re.findall(r"fogbayes (?:-q )?([a-z]+)", text):
        quoted |= options.get(cmd, set())
    return quoted


#: Commands that read a recording (all through cli._common.load_recording), and the column
#: roles whose flags the message must name (the time column renamed to a name without a
#: unit: 't_s' or 'time_ms' would be found and read by itself, fogbayes/data/time_units.py).
CASES = [("info", "time", "clock"), ("info", "output", "rate_dph"), ("fit", "output", "rate_dph"),
         ("fit", "time", "clock"), ("loop", "time", "clock")]


@pytest.mark.parametrize(("command", "column", "renamed"), CASES)
def test_missing_column_message_names_a_flag_the_command_accepts(command, column, renamed,
                                                                 tmp_path, capsys):
    rec = simulate("static", seed=0, duration=600.0, fs=1.0).recording
    path = tmp_path / "run.csv"
    fogbayes.save(rec, path)
    lines = path.read_text().split("\n")
    header = next(i for i, ln in enumerate(lines) if not ln.startswith("#"))
    lines[header] = ",".join(renamed if c == column else c for c in lines[header].split(","))
    path.write_text("\n".join(lines))
    args = {"info": [], "fit": ["-m", "bias-t", "--json", str(tmp_path / "f.json")],
            "loop": ["-m", "allan", "--json", str(tmp_path / "l.json"), "--max-steps", "0",
                     "--compensated", str(tmp_path / "c.csv")]}[command]
    assert main(["-q", command, str(path), *args]) == 2
    err = capsys.readouterr().err
    flags = FLAG.findall(err.split("Fix:", 1)[1])
    assert len(flags) == 1 and flags[0] in _options()[command], err
    code = main(["-q", command, str(path), *args, flags[0], renamed])
    assert code == 0, capsys.readouterr().err
