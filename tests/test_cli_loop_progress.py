"""``fogbayes loop`` shows its step and the candidate it is trying, on a terminal only.

* The loop reports its stages (:mod:`fogbayes.loop.progress`): the base fit, each step's
  screening and the refit of each shortlisted candidate (its place among them), the end.
  The candidates reported as refitted are the ones the result's evidence lists as
  refitted, in the same step.
* On a terminal the command line draws them (step of at most ``--max-steps``, stage,
  candidate); with stderr a file or a pipe nothing is drawn (one line per error holds).
"""

from __future__ import annotations

import io

import pytest
from rich.console import Console

from fogbayes.cli import _common, main
from fogbayes.data import save
from fogbayes.simulate import simulate


@pytest.fixture(scope="module")
def rec(tmp_path_factory):
    d = tmp_path_factory.mktemp("loopprogress")
    return save(simulate("thermal", seed=1, duration=1200.0, fs=1.0).recording, d / "rec.csv")


def test_the_loop_reports_its_steps_and_the_candidates_it_refits(rec):
    from fogbayes.data import load
    from fogbayes.loop import run_loop
    from fogbayes.loop.progress import listening

    stages = []
    with listening(stages.append):
        res = run_loop(load(rec), "bias-t", max_steps=2)
    assert stages[0].step == 0 and stages[0].what == "fitting the bias-t base"
    assert stages[-1].step is None  # finishing
    steps = [s.step for s in stages if s.step is not None]
    assert steps == sorted(steps) and all(0 <= k <= 2 for k in steps)
    assert {s.max_steps for s in stages} == {2}
    # the step the loop stopped in: its refits are the stop evidence's, in order tried
    last = max(steps)
    tried = [s for s in stages if s.step == last and s.candidate is not None
             and s.what.startswith("refitting")]
    refitted = [r["effect"] for r in res.stop.evidence["refitted"]]
    assert res.steps == [] and refitted, res.stop
    assert sorted(s.candidate for s in tried) == sorted(refitted)
    assert [s.index for s in tried] == list(range(1, len(tried) + 1))
    assert {s.total for s in tried} == {len(tried)}
    assert any(s.step == last and s.what.startswith("screening") for s in stages)


def test_a_terminal_shows_the_step_and_candidate(rec, tmp_path, monkeypatch, capsys):
    buf = io.StringIO()
    monkeypatch.setattr(_common, "console",
                        Console(file=buf, force_terminal=True, width=300, color_system=None))
    assert main(["loop", str(rec), "-m", "bias-t", "--max-steps", "1", "--json",
                 str(tmp_path / "l.json")]) == 0
    shown = buf.getvalue()
    assert "loop rec.csv, base model: fitting the bias-t base" in shown
    assert "loop rec.csv, step 1 of <=1: screening" in shown
    assert "loop rec.csv, step 1 of <=1: refitting " in shown and " (1 of " in shown
    assert "loop rec.csv, finishing: " in shown


def test_no_progress_when_stderr_is_not_a_terminal(rec, tmp_path, capsys):
    assert main(["loop", str(rec), "-m", "bias-t", "--max-steps", "1", "--json",
                 str(tmp_path / "l.json")]) == 0
    err = capsys.readouterr().err
    assert "step 1 of" not in err and "base model" not in err, err
    assert "" not in err.rstrip("\n").split("\n"), repr(err)
