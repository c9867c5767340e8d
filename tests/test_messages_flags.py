"""Every fix a message suggests is runnable: the flags it names exist.

Error messages end with 'Fix: ...', often naming a command-line flag. A flag that does
not exist (the old '--output-column', '--temperature-column') sends the user to a second
error. The checks: every '--flag' written in a string anywhere in fogbayes' source is an
option of some fogbayes command (and of the command whose module writes it); every flag
in the messages of the modules that read a recording is an option of every command that
reads one; each of those commands, handed a file wrong in each way lab files come wrong,
prints one line whose fix names only its own options; and the missing-column error of
each command that reads a recording names a flag that the same command then accepts, with
which it succeeds.
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


# -- every message reading a recording can print, on every command that reads one ---------
#: The modules :func:`fogbayes.data.load` runs: their messages reach every command that
#: reads a recording.
READING_MODULES = sorted([*(PACKAGE / "data").glob("_read.py"), PACKAGE / "data" / "io.py",
                          PACKAGE / "data" / "checks.py", PACKAGE / "data" / "units.py",
                          PACKAGE / "data" / "time_units.py",
                          PACKAGE / "data" / "temperature_columns.py",
                          *(PACKAGE / "data" / "logs").glob("*.py")])


def _message_flags(path: Path) -> set[str]:
    """Flags in the strings of ``path`` other than docstrings (messages, fixes, help)."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    docs = {id(node.body[0].value) for node in ast.walk(tree)
            if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef))
            and node.body and isinstance(node.body[0], ast.Expr)
            and isinstance(node.body[0].value, ast.Constant)}
    return {f for node in ast.walk(tree)
            if isinstance(node, ast.Constant) and isinstance(node.value, str)
            and id(node) not in docs for f in FLAG.findall(node.value)} - FOREIGN


def _readers() -> list[str]:
    return sorted(name for name, opts in _options().items() if "--time-unit" in opts)


@pytest.mark.parametrize("path", READING_MODULES,
                         ids=[str(p.relative_to(PACKAGE)) for p in READING_MODULES])
def test_reading_messages_name_options_of_every_reading_command(path):
    """A bad file gives the same message whichever command reads it, so every flag the
    reading modules name must be an option of each command that reads a recording (before:
    'plan' and 'pool' were told to use --temperature-scale, 'allan' --temperature, 'batch'
    and 'pool' --instance, none of which they had)."""
    options = _options()
    flags = _message_flags(path)
    missing = {cmd: sorted(flags - options[cmd]) for cmd in _readers()
               if flags - options[cmd]}
    assert missing == {}, f"{path.name}: flags these commands lack"


def _bad_files(tmp_path: Path) -> dict[str, Path]:
    """One recording written wrong in each way a lab file comes wrong."""
    rec = simulate("static", seed=0, duration=600.0, fs=1.0).recording
    good = tmp_path / "good.csv"
    fogbayes.save(rec, good)
    lines = good.read_text().splitlines()
    h = next(i for i, ln in enumerate(lines) if not ln.startswith("#"))
    meta, header, rows = lines[:h], lines[h], lines[h + 1:]

    def write(name, head=header, body=rows, more=()):
        keys = {m.split(":")[0] for m in more}
        path = tmp_path / name
        path.write_text("\n".join([*(m for m in meta if m.split(":")[0] not in keys), *more,
                                   head, *body]) + "\n")
        return path

    kelvin = [",".join([*r.split(",")[:2], repr(float(r.split(",")[2]) + 273.15)])
              for r in rows]
    return {
        "ragged": write("ragged.csv", body=[rows[0] + ",1", *rows[1:]]),
        "separator": write("separator.csv", head="time;output;T,degC",
                           body=[f"{k};{k % 3},{k % 7};20" for k in range(600)]),
        "decimal": write("decimal.csv", head=header.replace(",", ";"),
                         body=["0.0;1,5;20", *[r.replace(",", ";").replace(".", ",")
                                               for r in rows[1:]]]),
        "kelvin": write("kelvin.csv", body=kelvin),
        "listed": write("listed.csv", more=['# temperatures: ["temperature", "t_box"]']),
        "rate": write("rate.csv", more=["# sample_rate: 100"]),
        "unit": write("unit.csv", more=["# unit: furlong/fortnight"]),
        "output": write("output.csv", head=header.replace("output", "rate_dph")),
        "ms": write("ms.csv", body=[",".join([repr(float(r.split(",")[0]) * 1e3),
                                              *r.split(",")[1:]]) for r in rows]),
    }


def _invocation(command: str, bad: Path, tmp_path: Path, fit_doc: Path) -> list[str]:
    out = tmp_path / "out"
    return {"info": [str(bad)],
            "allan": [str(bad), "--json", f"{out}.json"],
            "arma": [str(bad), "--json", f"{out}.json"],
            "fit": [str(bad), "-m", "bias-t", "--json", f"{out}.json"],
            "loop": [str(bad), "-m", "allan", "--json", f"{out}.json", "--max-steps", "0",
                     "--compensated", f"{out}.csv"],
            "report": [str(bad), "-m", "bias-t", "--out", f"{out}.html"],
            "plan": [str(bad), "--term", "N", "--precision", "0.5"],
            "plan-chamber": [str(bad)],
            "pool": [str(bad), str(tmp_path / "good.csv"), "--json", f"{out}.json"],
            "compensate": [str(bad), "--params", str(fit_doc), "--out", f"{out}.csv"],
            "batch": [str(bad.parent / "batch"), "-m", "bias-t", "--out", str(tmp_path / "bo"),
                      "--json", "-"]}[command]


@pytest.fixture(scope="module")
def lab_files(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("bad")
    files = _bad_files(tmp)
    fit_doc = tmp / "fit.json"
    assert main(["-q", "fit", str(tmp / "good.csv"), "-m", "bias-t", "--json", str(fit_doc)]) == 0
    return tmp, files, fit_doc


@pytest.mark.parametrize("command", ["info", "allan", "arma", "fit", "loop", "report", "plan",
                                     "plan-chamber", "pool", "compensate", "batch"])
def test_every_reading_error_names_options_the_command_has(command, lab_files, capsys):
    """Each bad file through each command that reads a recording: one line, exit 2 (batch:
    the file's row in the summary), and every flag of the fix is an option of that command."""
    import json
    import shutil

    tmp, files, fit_doc = lab_files
    options = _options()[command] | _options()[""]
    for kind, bad in files.items():
        if command == "batch":
            folder = tmp / "batch"
            shutil.rmtree(folder, ignore_errors=True)
            folder.mkdir()
            shutil.copy(bad, folder / bad.name)
        code = main(["-q", command, *_invocation(command, bad, tmp, fit_doc)])
        out, err = capsys.readouterr()
        if command == "batch":
            assert code == 1, (kind, err)
            messages = [row["error"] for row in json.loads(out)["rows"]]
        else:
            assert code == 2, (kind, out, err)
            assert err.count("\n") == 1 and err.startswith("fogbayes: error:"), (kind, err)
            messages = [err]
        for message in messages:
            assert "Fix:" in message, (kind, message)
            flags = set(FLAG.findall(message.split("Fix:", 1)[1]))
            assert flags <= options, (kind, message)
