"""With stderr not a terminal (a log file, a pipe, CI), an error is exactly one line.

A progress bar drawn while stderr is a file left an empty line before the error; the bars
are now drawn only on a terminal. Failure paths with and without a bar active, through
the real entry point (``python -m fogbayes``, stderr a pipe) and in the process (stderr
captured: not a terminal either).
"""

from __future__ import annotations

import subprocess
import sys

import pytest

from fogbayes.cli import main
from fogbayes.data import save
from fogbayes.simulate import simulate


@pytest.fixture(scope="module")
def d(tmp_path_factory):
    d = tmp_path_factory.mktemp("oneline")
    rec = simulate("thermal", seed=1, duration=1200.0, fs=1.0).recording
    save(rec, d / "rec.csv")
    (d / "folder").mkdir()
    return d


def _cases(d):
    rec, t = d / "rec.csv", d / "out"
    return [
        # the bar of 'report' is up when the loop document turns out to be a folder
        (["report", rec, "--loop", d / "folder", "--out", t / "r.html"], "folder"),
        # the fit's bar is up when the orders are refused
        (["fit", rec, "-m", "bias-t", "--orders", "99", "--json", t / "f.json"], "99"),
        # ... and when the model finds no input_rate column
        (["fit", rec, "-m", "composite", "--json", t / "f.json"], "input_rate"),
        (["loop", rec, "-m", "composite", "--report", t / "l.html"], "input_rate"),
        # no bar: the file is not there
        (["fit", d / "missing.csv", "-m", "bias-t", "--json", t / "f.json"], "missing.csv"),
    ]


@pytest.mark.parametrize("k", range(5))
def test_an_error_is_one_line_when_stderr_is_captured(d, capsys, k):
    argv, named = _cases(d)[k]
    code = main([str(a) for a in argv])
    err = capsys.readouterr().err
    assert code == 2, err
    lines = err.split("\n")
    assert lines[-1] == "" and len(lines) == 2, repr(err)  # one line and its newline
    assert lines[0].startswith("fogbayes: error: ") and named in lines[0], repr(err)


def test_an_error_is_one_line_when_stderr_is_a_pipe(d):
    argv, named = _cases(d)[1]
    res = subprocess.run([sys.executable, "-m", "fogbayes", *map(str, argv)],
                         capture_output=True, text=True, timeout=300)
    assert res.returncode == 2, res.stderr
    assert res.stderr.count("\n") == 1 and res.stderr.startswith("fogbayes: error: "), \
        repr(res.stderr)
    assert named in res.stderr


def test_success_writes_no_empty_line(d, capsys):
    """The bar's empty line also came before the status lines of a command that worked."""
    assert main(["fit", str(d / "rec.csv"), "-m", "bias-t", "--json",
                 str(d / "out" / "ok.json")]) == 0
    err = capsys.readouterr().err
    assert err.strip() and "" not in err.rstrip("\n").split("\n"), repr(err)
