"""Each bad input gives its own fogbayes error naming file, column and row; never a crash."""

from __future__ import annotations

import string

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from fogbayes import errors
from fogbayes.data import Recording, load

GOOD = "time,output,temperature\n0,1.0,20\n1,1.1,20.1\n2,0.9,20.2\n"

CASES = [
    # (file text, error class, column, row)
    ("tim,output\n0,1\n1,2\n", errors.MissingColumnError, "time", None),
    ("time,output\n0,1\n1,abc\n", errors.NonNumericError, "output", 1),
    ("time,output\n0,1\n1,\n2,3\n", errors.NonFiniteError, "output", 1),
    ("time,output\n0,1\n1,nan\n", errors.NonFiniteError, "output", 1),
    ("time,output\n0,1\n1,inf\n", errors.NonFiniteError, "output", 1),
    ("time,output\n0,1\n1,2\n1,3\n", errors.TimeOrderError, "time", 2),
    ("time,output\n0,1\n2,2\n1,3\n", errors.TimeOrderError, "time", 2),
    ("", errors.EmptyRecordingError, None, None),
    ("time,output\n", errors.EmptyRecordingError, None, None),
    ("time,output,temperature\n0,1,x\n", errors.NonNumericError, "temperature", 0),
]


@pytest.mark.parametrize("text,cls,column,row", CASES)
def test_specific_error_names_file_column_row(tmp_path, text, cls, column, row):
    p = tmp_path / "bad.csv"
    p.write_text(text)
    with pytest.raises(cls) as info:
        load(p)
    e = info.value
    assert isinstance(e, ValueError)
    assert e.file == str(p) and str(p) in str(e)
    assert e.column == column and e.row == row
    assert "Fix:" in str(e)
    if row is not None:
        assert f"row {row} (line {row + 2})" in str(e)


def test_misnamed_column_suggests_the_close_name(tmp_path):
    p = tmp_path / "bad.csv"
    p.write_text("time,outptu\n0,1\n1,2\n")
    with pytest.raises(errors.MissingColumnError, match="did you mean 'outptu'"):
        load(p)


def test_unknown_unit_and_extension(tmp_path):
    p = tmp_path / "ok.csv"
    p.write_text(GOOD)
    with pytest.raises(errors.UnitError, match="unknown output unit 'furlongs'"):
        load(p, unit="furlongs")
    q = tmp_path / "data.xlsx"
    q.write_text("x")
    with pytest.raises(errors.FileFormatError, match="unknown file type"):
        load(q)
    with pytest.raises(errors.FileFormatError, match="not found"):
        load(tmp_path / "missing.csv")


def test_too_short_for_the_analysis():
    rec = Recording(time=np.arange(5.0), output=np.zeros(5))
    with pytest.raises(errors.TooShortError, match="needs at least 100 samples"):
        rec.require(100, "Allan deviation up to tau = 10 s")


def test_ragged_rows_are_a_format_error(tmp_path):
    p = tmp_path / "ragged.csv"
    p.write_text("time,output\n0,1\n1,2,3,4\n")
    with pytest.raises(errors.FileFormatError, match="cannot parse as CSV"):
        load(p)


def test_corrupt_binary_files(tmp_path):
    for ext in (".parquet", ".npz"):
        p = tmp_path / f"bad{ext}"
        p.write_bytes(b"\x00\x01not really a file")
        with pytest.raises(errors.FileFormatError):
            load(p)


_cell = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
    st.integers(-10, 10).map(str),
    st.text(alphabet=string.printable, max_size=6),
    st.just(""),
)
_row = st.lists(_cell, min_size=0, max_size=4).map(lambda cells: ",".join(cells))
_header = st.sampled_from(["time,output", "time,output,temperature", "t,output", "time,output,x", ""])


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(header=_header, rows=st.lists(_row, max_size=8), raw=st.binary(max_size=40), use_raw=st.booleans())
def test_malformed_csv_never_crashes(tmp_path, header, rows, raw, use_raw):
    """Whatever the bytes, load() either returns a valid Recording or raises a FogbayesError."""
    p = tmp_path / "fuzz.csv"
    if use_raw:
        p.write_bytes(raw)
    else:
        p.write_text("\n".join([header, *rows]) + "\n")
    try:
        rec = load(p)
    except errors.FogbayesError as e:
        assert str(p) in str(e)
        return
    assert rec.n >= 1
    assert np.all(np.isfinite(rec.output)) and np.all(np.diff(rec.time) > 0)
