"""NPZ files in the matrix layout (a 2-D 'data' array, its column names in 'columns', the
sample rate in 'fs_hz'), as data sets like the ADIS16405 static runs are distributed."""

from __future__ import annotations

import numpy as np
import pytest

from fogbayes import load
from fogbayes.errors import FogbayesError


def _write(path, data, columns, **extra):
    np.savez(path, data=data, columns=np.array(columns), **extra)
    return path


def test_columns_and_time_from_fs(tmp_path):
    data = np.arange(30, dtype=float).reshape(10, 3)
    f = _write(tmp_path / "m.npz", data, ["gx", "gy", "gz"], fs_hz=np.array(100.0))
    rec = load(f, output="gy", unit="deg/s")
    assert np.array_equal(rec.output, data[:, 1])
    assert np.allclose(rec.time, np.arange(10) / 100.0)
    assert rec.meta.sample_rate == 100.0
    assert "fs_hz" in rec.meta.extra["time"]


def test_a_time_column_of_its_own_is_kept(tmp_path):
    data = np.ones((5, 2))
    t = np.array([0.0, 0.5, 1.0, 1.5, 2.0])
    f = _write(tmp_path / "m.npz", data, ["a", "b"], fs_hz=np.array(2.0), time=t)
    assert np.array_equal(load(f, output="a").time, t)


@pytest.mark.parametrize("columns, key", [(["a", "b", "c"], "columns"), (["a", "a"], "a")])
def test_mismatched_or_repeated_names_are_refused(tmp_path, columns, key):
    f = _write(tmp_path / "m.npz", np.ones((5, 2)), columns, fs_hz=np.array(2.0))
    with pytest.raises(FogbayesError) as e:
        load(f, output="a")
    assert e.value.column == key and str(f) in str(e.value)


def test_a_bad_sample_rate_is_refused(tmp_path):
    f = _write(tmp_path / "m.npz", np.ones((5, 2)), ["a", "b"], fs_hz=np.array(-1.0))
    with pytest.raises(FogbayesError) as e:
        load(f, output="a")
    assert e.value.column == "fs_hz"


def test_string_arrays_other_than_column_names_stay_refused(tmp_path):
    f = tmp_path / "s.npz"
    np.savez(f, time=np.arange(3.0), output=np.array(["a", "b", "c"]))
    with pytest.raises(FogbayesError) as e:
        load(f)
    assert e.value.column == "output"
