"""`--json -` on the slower commands: the JSON document alone on stdout.

Each command runs in-process on the smallest record it accepts (a 10 min static record at
1 Hz for allan, 20 min of a simulated chamber test for the loop, a 15 min demo)
so that the whole file stays well under a minute; status lines go to stderr.
"""

from __future__ import annotations

import json

import pytest

from fogbayes.cli import main
from fogbayes.data import save
from fogbayes.simulate import simulate


def _run_json(capsys, args):
    code = main(args)
    cap = capsys.readouterr()
    assert code == 0, cap.err
    return json.loads(cap.out)  # fails on any text besides the one document


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("cli_json")
    save(simulate("static", seed=0, duration=600.0, fs=1.0).recording, d / "static.csv")
    save(simulate("thermal", seed=2, duration=1200.0, fs=1.0).recording, d / "run.csv")
    return d


def test_allan_json_to_stdout(capsys, files):
    doc = _run_json(capsys, ["allan", str(files / "static.csv"), "--json", "-"])
    assert doc["n"] == 600 and len(doc["tau"]) == len(doc["adev"]) > 3
    assert set(doc["fit"]["terms"]) >= {"N", "B"}


def test_loop_json_to_stdout(capsys, files, tmp_path):
    comp = tmp_path / "comp.csv"
    doc = _run_json(capsys, ["loop", str(files / "run.csv"), "-m", "bias-t", "--max-steps",
                             "1", "--json", "-", "--compensated", str(comp)])
    assert set(doc) >= {"model", "initial", "steps", "final", "unexplained"}
    assert len(comp.read_text().strip().splitlines()) == 1200 + 1  # every row + header


def test_demo_json_to_stdout(capsys, tmp_path):
    doc = _run_json(capsys, ["demo", "--out", str(tmp_path), "--duration", "900", "--fs", "1",
                             "--json", "-"])
    assert set(doc["models"]) == {"bias-t", "thermal"}
    assert (tmp_path / "report.html").exists() and doc["report"].endswith("report.html")
