"""Lean core, optional extras: without pyarrow (extra ``parquet``) or distributed (extra
``dask``) the features that need them fail with one line naming the extra, exit code 2,
and nothing is written; CSV, NPZ and the in-process engine work as before.

A missing package is simulated with ``sys.modules[name] = None``, which makes ``import
name`` raise ImportError (ModuleNotFoundError), as on an install without it.
"""

from __future__ import annotations

import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest

import fogbayes
from fogbayes.support.extras import DASK, PARQUET, require
from fogbayes.cli import main
from fogbayes.errors import FogbayesError, MissingExtraError

PARQUET_HINT = ("Parquet files need pyarrow, which is not installed. "
                "Fix: pip install 'fogbayes[parquet]'")
DASK_HINT = ("Batch runs with --engine dask need distributed, which is not installed. "
             "Fix: pip install 'fogbayes[dask]'")
ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture
def rec():
    t = np.arange(600) / 10.0
    y = np.random.default_rng(0).normal(0.0, 0.1, t.size)
    return fogbayes.Recording(time=t, output=y, temperatures=20.0 + 0.01 * t[:, None],
                              temperature_names=("temperature",))


@pytest.fixture
def no_pyarrow(monkeypatch):
    for name in ("pyarrow", "pyarrow.parquet"):
        monkeypatch.setitem(sys.modules, name, None)


@pytest.fixture
def no_dask(monkeypatch):
    for name in ("distributed", "dask"):
        monkeypatch.setitem(sys.modules, name, None)


def _one_error_line(capsys, hint: str) -> None:
    err = capsys.readouterr().err
    lines = [line for line in err.splitlines() if line.strip()]
    assert lines == [f"fogbayes: error: {hint}"], err


def test_info_on_a_parquet_file_names_the_extra(rec, tmp_path, capsys, monkeypatch):
    path = fogbayes.save(rec, tmp_path / "x.parquet")  # a real Parquet file, pyarrow present
    for name in ("pyarrow", "pyarrow.parquet"):
        monkeypatch.setitem(sys.modules, name, None)
    assert main(["info", str(path)]) == 2
    _one_error_line(capsys, PARQUET_HINT)


def test_save_parquet_names_the_extra_and_writes_nothing(rec, tmp_path, no_pyarrow):
    with pytest.raises(MissingExtraError) as info:
        fogbayes.save(rec, tmp_path / "x.parquet")
    assert str(info.value) == PARQUET_HINT
    assert isinstance(info.value, FogbayesError)
    assert list(tmp_path.iterdir()) == []  # no output, no temporary file left behind


def test_streamed_parquet_input_and_output_name_the_extra(rec, tmp_path, monkeypatch):
    from fogbayes.stream import open_source
    from fogbayes.stream.writers import open_sink

    src = fogbayes.save(rec, tmp_path / "big.parquet")
    for name in ("pyarrow", "pyarrow.parquet"):
        monkeypatch.setitem(sys.modules, name, None)
    with pytest.raises(MissingExtraError, match=r"fogbayes\[parquet\]"):
        open_source(src)
    with pytest.raises(MissingExtraError, match=r"fogbayes\[parquet\]"):
        open_sink(tmp_path / "out.parquet", 10, {"output": "float64"})
    assert sorted(p.name for p in tmp_path.iterdir()) == ["big.parquet"]


def test_batch_engine_dask_names_the_extra_before_any_work(rec, tmp_path, capsys, no_dask):
    runs = tmp_path / "runs"
    runs.mkdir()
    fogbayes.save(rec, runs / "a.csv")
    out = tmp_path / "fits"
    assert main(["batch", str(runs), "-m", "thermal", "--out", str(out), "--engine", "dask"]) == 2
    _one_error_line(capsys, DASK_HINT)
    assert not out.exists()


def test_csv_and_npz_work_without_the_extras(rec, tmp_path, capsys, monkeypatch, no_pyarrow):
    for name in ("distributed", "dask"):
        monkeypatch.setitem(sys.modules, name, None)
    for ext in ("csv", "npz"):
        path = fogbayes.save(rec, tmp_path / f"x.{ext}")
        back = fogbayes.load(path)
        np.testing.assert_array_equal(back.output, rec.output)
        np.testing.assert_array_equal(back.temperatures, rec.temperatures)
        capsys.readouterr()
        assert main(["info", str(path)]) == 0
        assert "error" not in capsys.readouterr().err


def test_require_returns_the_module_when_installed():
    import numpy

    assert require("numpy", "x", "Things") is numpy


def test_an_installed_but_broken_package_is_said_so(monkeypatch):
    import fogbayes.support.extras as opt

    def broken(name):
        raise ImportError("libarrow.so.2000: cannot open shared object file\nmore detail")

    monkeypatch.setattr(opt.importlib, "import_module", broken)
    with pytest.raises(MissingExtraError) as info:
        require("pyarrow.parquet", *PARQUET)
    msg = str(info.value)
    assert "installed but cannot be imported (libarrow.so.2000" in msg
    assert "\n" not in msg and "fogbayes[parquet]" in msg


def test_a_module_missing_inside_an_extra_is_not_blamed_on_it(monkeypatch):
    """ModuleNotFoundError for some other module (a dependency of the package) is not
    'the package is not installed'."""
    import fogbayes.support.extras as opt

    def inner(name):
        raise ModuleNotFoundError("No module named 'tornado'", name="tornado")

    monkeypatch.setattr(opt.importlib, "import_module", inner)
    with pytest.raises(MissingExtraError, match="installed but cannot be imported"):
        require("distributed", *DASK)


def test_pyproject_core_is_lean_and_test_pulls_the_extras():
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    core = " ".join(project["dependencies"])
    assert "pyarrow" not in core and "dask" not in core
    extras = project["optional-dependencies"]
    assert any(d.startswith("pyarrow") for d in extras["parquet"])
    assert any(d.startswith("dask[distributed]") for d in extras["dask"])
    for extra in ("all", "test"):
        assert any(d.replace(" ", "") == "fogbayes[parquet,dask]" for d in extras[extra])
