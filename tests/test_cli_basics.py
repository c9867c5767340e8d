"""The command line: bad input is one line on stderr and exit code 2, never a traceback."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

from fogbayes.cli import main
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


def test_unbuilt_command_says_so(capsys):
    assert main(["batch", "somewhere"]) == 1
    assert "not built yet" in capsys.readouterr().err
