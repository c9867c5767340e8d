"""A document that is JSON but not an object, or nested past the parser's stack, ends in one
``fogbayes: error:`` line naming the file (exit 2), never a traceback."""
import subprocess
import sys
from pathlib import Path

import numpy as np


def _rec(tmp_path: Path) -> Path:
    rec = tmp_path / "rec.csv"
    t = np.arange(200.0)
    rec.write_text("time,output\n" + "".join(f"{a},{b}\n" for a, b in zip(t, np.sin(t))))
    return rec


def _run(tmp_path, *args):
    return subprocess.run([sys.executable, "-m", "fogbayes", *args], cwd=tmp_path,
                          capture_output=True, text=True, timeout=120)


def test_report_loop_given_a_json_list_is_one_line(tmp_path):
    _rec(tmp_path)
    (tmp_path / "list.json").write_text("[1, 2, 3]")
    res = _run(tmp_path, "report", "rec.csv", "--loop", "list.json", "-o", "r.html")
    assert res.returncode == 2, res.stderr
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("fogbayes: error:"), res.stderr
    assert "list.json" in lines[0] and "Traceback" not in res.stderr


def test_report_loop_given_deep_nesting_is_one_line(tmp_path):
    _rec(tmp_path)
    (tmp_path / "deep.json").write_text("[" * 100_000 + "]" * 100_000)
    res = _run(tmp_path, "report", "rec.csv", "--loop", "deep.json", "-o", "r.html")
    assert res.returncode == 2, res.stderr
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and "deep.json" in lines[0], res.stderr


def test_loop_noise_prior_given_deep_nesting_is_one_line(tmp_path):
    _rec(tmp_path)
    (tmp_path / "deep.json").write_text("[" * 100_000 + "]" * 100_000)
    res = _run(tmp_path, "loop", "rec.csv", "-m", "allan", "--noise-prior", "deep.json",
               "--json", "l.json", "--compensated", "c.csv")
    assert res.returncode == 2, res.stderr
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and "deep.json" in lines[0], res.stderr
    assert "Traceback" not in res.stderr
