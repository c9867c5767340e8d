"""The command line: bad input is one line on stderr and exit code 2, never a traceback."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest
import typer.main

from fogbayes.cli import app, main
from fogbayes.data import Recording, save

BAD = {
    "missing_column.csv": "tim,output\n0,1\n1,2\n",
    "non_numeric.csv": "time,output\n0,1\n1,abc\n",
    "nan.csv": "time,output\n0,1\n1,nan\n",
    "duplicate_time.csv": "time,output\n0,1\n0,2\n",
    "empty.csv": "",
}


@pytest.mark.parametrize("name", sorted(BAD))
def test_bad_input_exit_code_2_one_line(tmp_path, capsys, name):
    p = tmp_path / name
    p.write_text(BAD[name])
    assert main(["info", str(p)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("fogbayes: error: ") and str(p) in err[0]
    assert "Traceback" not in err[0]


def test_unknown_unit_exit_code_2(tmp_path, capsys):
    p = save(Recording(time=np.arange(3.0), output=np.zeros(3)), tmp_path / "ok.csv")
    assert main(["info", str(p), "--output-unit", "parsecs"]) == 2
    assert "unknown output unit" in capsys.readouterr().err


def test_info_json_to_stdout(tmp_path, capsys):
    t = np.r_[np.arange(10.0), np.arange(15.0, 20.0)]
    p = save(Recording(time=t, output=np.ones(15), temperatures=np.full(15, 21.0)), tmp_path / "g.csv")
    assert main(["info", str(p), "--json", "-"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["n"] == 15 and len(doc["gaps"]) == 1 and doc["gaps"][0]["duration_s"] == 6.0
    assert doc["temperatures"]["temperature"] == {"min": 21.0, "max": 21.0}


def test_script_prints_no_traceback(tmp_path):
    p = tmp_path / "bad.csv"
    p.write_text(BAD["non_numeric.csv"])
    r = subprocess.run([sys.executable, "-m", "fogbayes", "info", str(p)], capture_output=True, text=True)
    assert r.returncode == 2 and "Traceback" not in r.stderr and "row 1 (line 3)" in r.stderr


def test_help_lists_commands(capsys):
    assert main(["--help"]) == 0
    out = capsys.readouterr().out
    assert "info" in out


# ------------------------------------------------------------------ help, flags, --json -
# Consistency of the command line (issue #8): every command documents an example, accepts
# -q/--quiet after its name, and writes its JSON document alone on stdout with `--json -`.

COMMANDS = sorted(typer.main.get_command(app).commands)


def test_all_design_commands_are_registered():
    # docs/DESIGN.md's commands plus the helpers; a lost registration would silently drop one
    assert {"allan", "arma", "batch", "compensate", "demo", "fit", "info", "loop", "report",
            "simulate"} <= set(COMMANDS)


def test_root_help_documents_exit_codes_and_examples(capsys):
    assert main(["--help"]) == 0
    out = " ".join(capsys.readouterr().out.split())  # undo rich's line wrapping
    for text in ("Exit codes: 0 success", "1 the work failed", "2 bad input", "--json -",
                 "Examples:", "fogbayes demo"):
        assert text in out, text


@pytest.mark.parametrize("name", COMMANDS)
def test_every_command_help_has_an_example(capsys, name):
    assert main([name, "--help"]) == 0
    out = capsys.readouterr().out
    assert "Example" in out and f"fogbayes {name}" in out.split("Example", 1)[1]


@pytest.mark.parametrize("flag", ["--quiet", "-q"])
@pytest.mark.parametrize("name", COMMANDS)
def test_quiet_is_accepted_after_every_command(capsys, name, flag):
    # click rejects an unknown option while parsing (exit 2), before --help is handled
    assert main([name, flag, "--help"]) == 0
    assert "No such option" not in capsys.readouterr().err


def _run_json(capsys, args):
    """Run one command with `--json -`; its stdout must be one JSON document and nothing else."""
    code = main(args)
    cap = capsys.readouterr()
    assert code == 0, cap.err
    return json.loads(cap.out), cap.err  # json.loads fails on any extra text


@pytest.fixture(scope="module")
def chamber(tmp_path_factory):
    """A 20 min, 1 Hz simulated chamber test (a few thousand rows keep every fit cheap)."""
    from fogbayes.simulate import simulate

    p = tmp_path_factory.mktemp("cli") / "run.csv"
    save(simulate("thermal", seed=2, duration=1200.0, fs=1.0).recording, p)
    return p


def test_simulate_info_fit_compensate_json_to_stdout(tmp_path, capsys, chamber):
    rec = tmp_path / "sim.csv"
    truth, _ = _run_json(capsys, ["simulate", "thermal", "--duration", "600", "--fs", "1",
                                  "--seed", "4", "--out", str(rec), "--json", "-"])
    assert truth["scenario"] == "thermal" and truth["seed"] == 4 and rec.exists()

    info, _ = _run_json(capsys, ["info", str(rec), "--json", "-"])
    assert info["n"] == 600 and info["unit"] == "deg/h"

    fit, err = _run_json(capsys, ["fit", str(chamber), "-m", "bias-t", "--json", "-"])
    assert fit["model"] == "bias-t" and "converged=" in err  # status line went to stderr
    fit_path = tmp_path / "fit.json"
    fit_path.write_text(json.dumps(fit))

    out_csv = tmp_path / "comp.csv"
    comp, _ = _run_json(capsys, ["compensate", str(chamber), "-p", str(fit_path), "-o",
                                 str(out_csv), "--json", "-"])
    n_rows = len(out_csv.read_text().strip().splitlines()) - 1
    assert comp["rows"] == n_rows == 1200 and comp["model"] == "bias-t"
    # the summary's before/after are the fit document's (same data, same compensation)
    assert comp["metrics"]["stability"][0]["after"] == pytest.approx(
        fit["metrics"]["full"]["stability"][0]["after"], rel=1e-9)


def test_quiet_after_the_command_silences_stderr(tmp_path, capsys, chamber):
    assert main(["fit", str(chamber), "-m", "bias-t", "--json", str(tmp_path / "f.json")]) == 0
    assert "converged=" in capsys.readouterr().err  # status lines without --quiet ...
    assert main(["fit", str(chamber), "-m", "bias-t", "--json", str(tmp_path / "f.json"),
                 "-q"]) == 0
    cap = capsys.readouterr()
    assert cap.err == "" and cap.out == ""  # ... and none with it
    assert main(["info", str(chamber), "--quiet"]) == 0  # results still go to stdout
    out = capsys.readouterr().out
    assert " samples, " in out and "temperature: " in out and " degC" in out


def test_arma_json_to_stdout(capsys, tmp_path):
    from fogbayes.simulate import simulate

    static = save(simulate("static", seed=0, duration=600.0, fs=1.0).recording,
                  tmp_path / "static.csv")
    # two candidates, not five: the compile time of each candidate dominates at this size
    doc, _ = _run_json(capsys, ["arma", str(static), "--candidates", "1,0;1,1", "--json", "-"])
    assert doc["selected"] in ("AR(1)", "ARMA(1,1)") and doc["file"].endswith("static.csv")
