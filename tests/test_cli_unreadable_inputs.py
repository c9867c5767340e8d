"""An input the user cannot read, or a folder where a document goes, is one line.

typer checks a ``Path`` parameter's readability itself and fails with click's multi-line
usage box; the commands now say it as every other bad input: one ``fogbayes: error:``
line naming the file and a fix, exit 2 (:func:`fogbayes.cli._common.check_inputs`).

The files are ``chmod 000``. Root reads through permission bits, so as root the commands
run under ``capsh`` without CAP_DAC_OVERRIDE and CAP_DAC_READ_SEARCH (as a user would);
all cases run in one interpreter, each with its own stderr.
"""

from __future__ import annotations

import json
import os
import shlex
import shutil
import subprocess
import sys
import textwrap

import pytest

from fogbayes.cli import main
from fogbayes.data import save
from fogbayes.simulate import simulate

SCRIPT = textwrap.dedent("""
    import io, json, sys
    from fogbayes.cli import main
    out = []
    for argv in json.loads(sys.argv[1]):
        err, sys.stderr = sys.stderr, io.StringIO()
        try:
            code = main(argv)
        finally:
            text, sys.stderr = sys.stderr.getvalue(), err
        out.append([code, text])
    print(json.dumps(out))
""")


def _runner(probe: str) -> list[str] | None:
    """The command prefix under which ``probe`` (a chmod 000 file) cannot be read."""
    if os.geteuid() != 0:
        return []
    capsh = shutil.which("capsh")
    if capsh is None:
        return None
    prefix = [capsh, "--drop=cap_dac_override,cap_dac_read_search", "--", "-c"]
    res = subprocess.run([*prefix, shlex.join(["cat", probe])], capture_output=True)
    return prefix if res.returncode != 0 else None


@pytest.fixture(scope="module")
def d(tmp_path_factory):
    d = tmp_path_factory.mktemp("unreadable")
    rec = simulate("thermal", seed=1, duration=1200.0, fs=1.0).recording
    save(rec, d / "rec.csv")
    save(rec, d / "locked.csv")
    assert main(["-q", "fit", str(d / "rec.csv"), "-m", "bias-t", "--json",
                 str(d / "fit.json")]) == 0
    shutil.copy(d / "fit.json", d / "locked_fit.json")
    (d / "locked_prior.json").write_text('{"K": 0.02}')
    (d / "locked_folder").mkdir()
    shutil.copy(d / "rec.csv", d / "locked_folder" / "rec.csv")
    (d / "folder.json").mkdir()
    for name in ("locked.csv", "locked_fit.json", "locked_prior.json", "locked_folder"):
        (d / name).chmod(0)
    yield d
    (d / "locked_folder").chmod(0o755)


def _cases(d):
    o = d / "out"
    return [
        # (argv, the file the line must name)
        (["fit", d / "locked.csv", "-m", "bias-t", "--json", o / "f.json"], "locked.csv"),
        (["info", d / "locked.csv"], "locked.csv"),
        (["compensate", d / "rec.csv", "-p", d / "locked_fit.json", "-o", o / "c.csv"],
         "locked_fit.json"),
        (["report", d / "rec.csv", "--fit", d / "locked_fit.json", "--out", o / "r.html"],
         "locked_fit.json"),
        (["loop", d / "rec.csv", "-m", "bias-t", "--noise-prior", d / "locked_prior.json",
          "--json", o / "l.json"], "locked_prior.json"),
        (["allan", d / "rec.csv", "--bayes", "--prior", d / "locked_prior.json", "--json",
          o / "a.json"], "locked_prior.json"),
        (["pool", d / "locked.csv", d / "rec.csv", "-m", "bias-t", "--json", o / "p.json"],
         "locked.csv"),
        (["batch", d / "locked_folder", "-m", "bias-t", "--out", o / "b"], "locked_folder"),
    ]


def test_an_unreadable_input_is_one_line_naming_it(d):
    prefix = _runner(str(d / "locked.csv"))
    if prefix is None:
        pytest.skip("running as root without capsh: every file is readable")
    cases = _cases(d)
    argvs = json.dumps([["-q", *map(str, argv)] for argv, _ in cases])
    cmd = [sys.executable, "-c", SCRIPT, argvs]
    if prefix:
        cmd = [*prefix, shlex.join(cmd)]
    res = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    assert res.returncode == 0, res.stderr
    results = json.loads(res.stdout.strip().splitlines()[-1])
    for (argv, named), (code, err) in zip(cases, results):
        lines = err.splitlines()
        assert code == 2, (argv[0], err)
        assert len(lines) == 1 and lines[0].startswith("fogbayes: error: "), (argv[0], err)
        assert named in lines[0] and "cannot be read" in lines[0], (argv[0], err)
        assert "Fix: make it readable (chmod u+r" in lines[0], (argv[0], err)
        assert not (d / "out").exists()


@pytest.mark.parametrize("argv", [
    ["compensate", "REC", "-p", "FOLDER", "-o", "OUT/c.csv"],
    ["report", "REC", "--fit", "FOLDER", "--out", "OUT/r.html"],
    ["loop", "REC", "-m", "bias-t", "--noise-prior", "FOLDER", "--json", "OUT/l.json"],
])
def test_a_folder_where_a_document_goes_is_one_line(d, capsys, argv):
    argv = [a.replace("REC", str(d / "rec.csv")).replace("FOLDER", str(d / "folder.json"))
            .replace("OUT", str(d / "out")) for a in argv]
    code = main(argv)
    err = capsys.readouterr().err.splitlines()
    assert code == 2 and len(err) == 1, err
    assert err[0].startswith(f"fogbayes: error: {d / 'folder.json'}: "), err
    assert "is a folder, not a file. Fix: name the JSON file itself" in err[0], err


@pytest.mark.parametrize("command", [["info"], ["fit", "-m", "bias-t"], ["allan", "--json"]])
def test_a_folder_given_as_the_recording_is_called_a_folder(tmp_path, capsys, command):
    """A plain folder (not a ROS 2 bag) was "unknown file type ''"; now it is named a folder
    and the fix points to one file in it or to the commands that take folders."""
    folder = tmp_path / "runs"
    folder.mkdir()
    tail = [*command[1:], str(tmp_path / "a.json")] if command[-1] == "--json" else command[1:]
    code = main([command[0], str(folder), *tail])
    err = capsys.readouterr().err.strip()
    assert code == 2
    assert len(err.splitlines()) == 1, err
    assert "runs: a folder, not a recording" in err and "fogbayes pool" in err
