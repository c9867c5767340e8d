"""``fogbayes loop`` writes the outputs asked for, and only those.

``--report`` alone is enough (no ``--json`` or ``--compensated`` demanded); an output not
asked for is not written anywhere; asking for none is one line naming the options.
"""

from __future__ import annotations

import pytest

from fogbayes.cli import main
from fogbayes.data import save
from fogbayes.simulate import simulate


@pytest.fixture(scope="module")
def rec(tmp_path_factory):
    d = tmp_path_factory.mktemp("loopout")
    recording = simulate("thermal", seed=1, duration=1200.0, fs=1.0).recording
    return save(recording, d / "rec.csv")


def test_report_alone_is_enough_and_nothing_else_is_written(rec, tmp_path, capsys,
                                                             monkeypatch):
    monkeypatch.chdir(tmp_path)  # a default output would land here
    out = tmp_path / "out"
    out.mkdir()
    code = main(["loop", str(rec), "-m", "bias-t", "--report", str(out / "loop.html")])
    err = capsys.readouterr().err
    assert code == 0, err
    assert sorted(p.name for p in tmp_path.rglob("*")) == ["loop.html", "out"]
    html = (out / "loop.html").read_text(encoding="utf-8")
    assert "<html" in html.lower() and "Closed loop: rec.csv" in html
    assert f"wrote {out / 'loop.html'}" in err
    assert "wrote" not in err.replace(f"wrote {out / 'loop.html'}", "")


def test_json_alone_writes_only_the_json(rec, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    code = main(["-q", "loop", str(rec), "-m", "bias-t", "--max-steps", "0", "--json",
                 "loop.json"])
    assert code == 0, capsys.readouterr().err
    assert [p.name for p in tmp_path.iterdir()] == ["loop.json"]


def test_no_output_asked_for_is_one_line_naming_the_options(rec, tmp_path, capsys,
                                                           monkeypatch):
    monkeypatch.chdir(tmp_path)
    code = main(["loop", str(rec), "-m", "bias-t"])
    err = capsys.readouterr().err.splitlines()
    assert code == 2 and len(err) == 1, err
    assert err[0].startswith("fogbayes: error: ") and "nothing to write" in err[0], err
    for flag in ("--report", "--json", "--compensated"):
        assert flag in err[0], err
    assert list(tmp_path.iterdir()) == []


def test_help_says_which_outputs_are_written(capsys):
    main(["loop", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "at least one" in text and "nothing else" in text, text
    assert "fogbayes loop chamber.csv -m bias-t --report loop.html" in text
