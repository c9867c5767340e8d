"""A usage error (missing option or argument, unknown command or option, invalid value) is
one ``fogbayes: error:`` line naming the command and its ``--help``, exit 2 -- not click's
multi-line usage box. Help itself is unchanged: ``--help`` exits 0, ``fogbayes`` alone
shows the command list (exit 2, as click does)."""

from __future__ import annotations

import pytest

from fogbayes.cli import main


@pytest.mark.parametrize("argv, command, says", [
    (["fit"], "fogbayes fit", "Missing argument"),
    (["fit", "rec.csv"], "fogbayes fit", "Missing option '--model'"),
    (["nosuch"], "fogbayes", "No such command 'nosuch'"),
    (["fitt", "rec.csv"], "fogbayes", "Did you mean 'fit'?"),
    (["fit", "rec.csv", "-m", "bias-t", "--json", "f.json", "--bogus"], "fogbayes fit",
     "No such option: --bogus"),
    (["loop", "rec.csv", "-m", "bias-t", "--max-steps", "-1", "--report", "r.html"],
     "fogbayes loop", "Invalid value for '--max-steps'"),
])
def test_a_usage_error_is_one_line(tmp_path, monkeypatch, capsys, argv, command, says):
    monkeypatch.chdir(tmp_path)
    code = main(argv)
    out, err = capsys.readouterr()
    assert code == 2, err
    lines = err.splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith(f"fogbayes: error: {command}: "), err
    assert says in lines[0], err
    assert lines[0].endswith(f"Fix: see '{command} --help'"), err
    assert out == "" and list(tmp_path.iterdir()) == []


def test_help_is_unchanged(capsys):
    assert main(["fit", "--help"]) == 0
    assert "Usage: fogbayes fit" in " ".join(capsys.readouterr().out.split())
    assert main([]) == 2
    out = " ".join(capsys.readouterr().out.split())
    assert "Usage: fogbayes" in out and "loop" in out
