"""The README's command-line tour runs, in order, exactly as written.

The block under "### Command line" is run by bash (``set -euo pipefail``) in an empty
folder with the installed ``fogbayes`` script. A command whose flags, inputs or outputs
drifted from the code fails here with the line that broke.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
from pathlib import Path

import pytest

README = Path(__file__).resolve().parents[1] / "README.md"


def tour_commands() -> str:
    section = README.read_text(encoding="utf-8").split("### Command line", 1)[1]
    return re.search(r"^```\n(.*?)^```", section, flags=re.S | re.M).group(1)


def test_tour_block_is_found_and_starts_with_the_demo():
    lines = tour_commands().strip().splitlines()
    assert lines[0].startswith("fogbayes demo") and len(lines) >= 10


def test_readme_tour_runs_in_order(tmp_path):
    if shutil.which("fogbayes") is None:
        msg = "the fogbayes script is not on PATH (pip install -e .)"
        if os.environ.get("CI"):
            pytest.fail(msg)
        pytest.skip(msg)
    script = "set -euo pipefail\nset -x\n" + tour_commands()
    env = {**os.environ, "MPLBACKEND": "Agg"}
    r = subprocess.run(["bash", "-c", script], cwd=tmp_path, capture_output=True, text=True,
                       env=env, timeout=900)
    last = [ln for ln in r.stderr.splitlines() if ln.startswith("+ ")][-1:]
    assert r.returncode == 0, f"tour stopped at {last}: {r.stderr[-2000:]}"
    for made in ("demo_out/report.html", "fit.json", "compensated.csv", "report.html",
                 "loop.json", "loop.html", "adev.json", "adev.png", "imu.yaml", "l2.json",
                 "fits/summary.json"):
        assert (tmp_path / made).stat().st_size > 0, made
