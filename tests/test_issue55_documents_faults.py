"""Faults in a recording's metadata end in one line naming the file (issue 55).

* a CSV ``# key:`` line with nothing after the colon (a value forgotten) is refused with the
  file and its line, whichever argument would have overridden it;
* an NPZ whose ``__meta__`` is a pickled object is refused by every reader, the streaming
  one included, without unpickling it.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from fogbayes import load, save
from fogbayes.cli import main
from fogbayes.errors import MetadataError
from fogbayes.simulate import simulate


def run(capsys, *args) -> tuple[int, str]:
    capsys.readouterr()
    rc = main([str(a) for a in args])
    return rc, capsys.readouterr().err


def one_line(err: str) -> str:
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("fogbayes: error:"), err
    assert "Traceback" not in err
    return lines[0]


def _csv(path, header_lines: str):
    t = np.arange(100.0)
    path.write_text(header_lines + "time,output\n" + "".join(f"{a},{0.01 * a}\n" for a in t))
    return path


@pytest.mark.parametrize("key,line_no", [("unit", 2), ("sensor_id", 2), ("sample_rate", 2),
                                         ("scale_factor", 2)])
def test_blank_metadata_line_is_refused(tmp_path, capsys, key, line_no):
    f = _csv(tmp_path / "blank.csv", f"# comment: a lab note\n# {key}:\n")
    rc, err = run(capsys, "info", f)
    assert rc == 2
    line = one_line(err)
    assert str(f) in line and f"line {line_no}" in line and f"'# {key}:' has no value" in line
    assert f"Fix: write the value, e.g. '# {key}: " in line and "or delete the line" in line


def test_blank_unit_is_refused_even_with_an_override(tmp_path):
    """--output-unit (unit=) would hide the forgotten value: the file is still wrong."""
    f = _csv(tmp_path / "blank.csv", "# unit:   \n")
    with pytest.raises(MetadataError, match=r"line 1: '# unit:' has no value"):
        load(f, unit="deg/s")


def test_written_metadata_still_reads(tmp_path):
    """What fogbayes.save writes (and a key fogbayes does not read, left blank) loads."""
    rec = simulate("static", duration=200.0, fs=1.0, seed=1).recording
    save(rec, tmp_path / "ok.csv")
    back = load(tmp_path / "ok.csv")
    assert back.unit == rec.unit and back.meta.sensor_id == rec.meta.sensor_id
    f = _csv(tmp_path / "note.csv", "# operator:\n# unit: deg/s\n")
    assert load(f).unit == "deg/s"


def _pickled_meta_npz(path):
    rec = simulate("thermal", duration=600.0, fs=1.0, seed=2).recording
    np.savez(path, time=rec.time, output=rec.output, temperature=rec.temperatures[:, 0],
             __meta__=np.array({"unit": "deg/h"}, dtype=object))  # a pickle inside the zip
    return path


@pytest.fixture(scope="module")
def fit_doc(tmp_path_factory):
    d = tmp_path_factory.mktemp("fit")
    rec = simulate("thermal", duration=1800.0, fs=1.0, seed=2).recording
    save(rec, d / "rec.csv")
    assert main(["-q", "fit", str(d / "rec.csv"), "-m", "bias-t", "--temperature",
                 "temperature", "--json", str(d / "fit.json")]) == 0
    assert json.loads((d / "fit.json").read_text())["model"] == "bias-t"
    return d / "fit.json"


def test_pickled_npz_meta_streamed_is_one_line(tmp_path, capsys, fit_doc):
    f = _pickled_meta_npz(tmp_path / "pickled.npz")
    rc, err = run(capsys, "compensate", f, "-p", fit_doc, "-o", tmp_path / "c.npz", "--stream")
    assert rc == 2
    line = one_line(err)
    assert str(f) in line and "__meta__" in line and "Fix:" in line
    assert not (tmp_path / "c.npz").exists()


def test_pickled_npz_meta_loaded_is_one_line(tmp_path, capsys):
    f = _pickled_meta_npz(tmp_path / "pickled.npz")
    rc, err = run(capsys, "info", f)
    assert rc == 2 and str(f) in one_line(err) and "__meta__" in err


def test_npz_meta_not_json_streamed_is_one_line(tmp_path, capsys, fit_doc):
    rec = simulate("thermal", duration=600.0, fs=1.0, seed=2).recording
    f = tmp_path / "badjson.npz"
    np.savez(f, time=rec.time, output=rec.output, temperature=rec.temperatures[:, 0],
             __meta__=np.array('{"unit": "deg/h"'))
    rc, err = run(capsys, "compensate", f, "-p", fit_doc, "-o", tmp_path / "c.npz", "--stream")
    assert rc == 2 and str(f) in one_line(err) and "not JSON" in err


def test_stream_metadata_not_an_object_is_one_line(tmp_path, capsys, fit_doc):
    """The streaming readers check metadata as the loaders do: a meta.json of a .npy folder
    that is a list, Parquet schema metadata that is not JSON."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    rec = simulate("thermal", duration=600.0, fs=1.0, seed=2).recording
    folder = tmp_path / "npy"
    folder.mkdir()
    for name, col in (("time", rec.time), ("output", rec.output),
                      ("temperature", rec.temperatures[:, 0])):
        np.save(folder / f"{name}.npy", col)
    (folder / "meta.json").write_text("[1, 2]")
    rc, err = run(capsys, "compensate", folder, "-p", fit_doc, "-o", tmp_path / "c.npz",
                  "--stream")
    assert rc == 2 and "meta.json" in one_line(err) and "not an object" in err
    table = pa.table({"time": rec.time, "output": rec.output,
                      "temperature": rec.temperatures[:, 0]})
    pq.write_table(table.replace_schema_metadata({b"fogbayes": b"[1"}), tmp_path / "m.parquet")
    rc, err = run(capsys, "compensate", tmp_path / "m.parquet", "-p", fit_doc, "-o",
                  tmp_path / "c.parquet", "--stream")
    assert rc == 2 and str(tmp_path / "m.parquet") in one_line(err) and "not JSON" in err
