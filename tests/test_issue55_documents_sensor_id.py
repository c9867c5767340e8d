"""A sensor id is text from the file to the report and the JSON (issue 55).

``0070`` in a CSV's ``# sensor_id:`` line is the id printed on the unit; read as a number
it would become ``70``, another unit. Every place that shows or stores it must keep the
four characters as written.
"""

from __future__ import annotations

import json
import re

import numpy as np

from fogbayes import load, save
from fogbayes.cli import main
from fogbayes.render.html import fmt, table_html
from fogbayes.simulate import simulate

ID = "0070"


def _csv(tmp_path):
    rec = simulate("static", duration=1200.0, fs=1.0, seed=4).recording
    save(rec, tmp_path / "raw.csv")
    text = (tmp_path / "raw.csv").read_text()
    text = re.sub(r"(?m)^# sensor_id: .*$", f"# sensor_id: {ID}", text)
    assert f"# sensor_id: {ID}\n" in text
    (tmp_path / "unit.csv").write_text(text)
    return tmp_path / "unit.csv"


def test_report_shows_the_id_as_written(tmp_path):
    f = _csv(tmp_path)
    assert main(["-q", "report", str(f), "-o", str(tmp_path / "r.html")]) == 0
    page = (tmp_path / "r.html").read_text()
    cell = re.search(r"<td>sensor</td><td>([^<]*)</td>", page)
    assert cell is not None and cell.group(1) == ID
    assert f"<b>{ID}</b>" in page  # the headline
    assert "<td>sensor</td><td>70</td>" not in page


def test_documents_keep_the_id(tmp_path):
    f = _csv(tmp_path)
    assert main(["-q", "info", str(f), "--json", str(tmp_path / "i.json")]) == 0
    assert main(["-q", "allan", str(f), "--json", str(tmp_path / "a.json")]) == 0
    for name in ("i.json", "a.json"):
        assert json.loads((tmp_path / name).read_text())["sensor_id"] == ID


def test_saved_files_keep_the_id(tmp_path):
    rec = load(_csv(tmp_path))
    assert rec.meta.sensor_id == ID
    for ext in ("npz", "parquet", "csv"):
        save(rec, tmp_path / f"back.{ext}")
        assert load(tmp_path / f"back.{ext}").meta.sensor_id == ID


def test_table_text_is_never_reparsed():
    """fmt's contract: numbers are formatted, text is shown as it is."""
    assert fmt(ID) == ID and fmt("1e3") == "1e3"
    assert fmt(np.float64(0.000247812)) == "0.0002478" and fmt(70) == "70"
    assert f"<td>{ID}</td>" in table_html(["sensor"], [[ID]])
