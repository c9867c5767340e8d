"""A refused output path's suggestion keeps the kind of file the flag writes."""
import subprocess
import sys
from pathlib import Path

import numpy as np


def test_fit_json_onto_recording_suggests_a_json_name(tmp_path: Path):
    rec = tmp_path / "rec.csv"
    t = np.arange(200.0)
    rec.write_text("time,output\n" + "".join(f"{a},{b}\n" for a, b in zip(t, np.sin(t))))
    res = subprocess.run([sys.executable, "-m", "fogbayes", "fit", "rec.csv", "-m", "allan",
                          "--json", "rec.csv"], cwd=tmp_path, capture_output=True, text=True,
                         timeout=120)
    assert res.returncode == 2
    assert "rec_out.json" in res.stderr
    assert "rec_out.csv" not in res.stderr
    assert not (tmp_path / "rec_out.json").exists()
