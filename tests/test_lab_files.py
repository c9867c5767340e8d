"""Lab files as they come: European CSV (';' and decimal commas), tab-separated files, and
time columns in ms or us.

The reference for every file written here is the same recording saved by
:func:`fogbayes.save` (',' and '.', time in seconds): a file read in another dialect or
unit must give the same numbers, bit for bit where the text holds the same digits. Where a
reading is ambiguous or the time looks like a ms counter, the one-line error or the `info`
output must name the option that fixes it, and that option must then work.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

import fogbayes
from fogbayes.cli import main
from fogbayes.simulate import simulate


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """A 1 h, 1 Hz thermal recording with two temperature channels, as fogbayes writes it."""
    rec = simulate("thermal", seed=3, duration=3600.0, fs=1.0).recording
    path = tmp_path_factory.mktemp("ref") / "ref.csv"
    fogbayes.save(rec, path)
    return path


def _rewrite(reference, path, *, sep=",", decimal=".", time_factor=None, time_name=None,
             drop_rate=False):
    """``reference`` rewritten with another separator/decimal mark, time unit or name."""
    lines = reference.read_text().splitlines()
    h = next(i for i, ln in enumerate(lines) if not ln.startswith("#"))
    meta = [ln for ln in lines[:h] if not (drop_rate and "sample_rate" in ln)]
    names = lines[h].split(",")
    if time_name is not None:
        names[0] = time_name
    rows = []
    for ln in lines[h + 1:]:
        cells = ln.split(",")
        if time_factor is not None:
            cells[0] = repr(float(cells[0]) * time_factor)
        rows.append(sep.join(c.replace(".", decimal) for c in cells))
    path.write_text("\n".join(meta + [sep.join(names)] + rows) + "\n", encoding="utf-8")
    return path


def _same(a, b):
    np.testing.assert_array_equal(a.time, b.time)
    np.testing.assert_array_equal(a.output, b.output)
    np.testing.assert_array_equal(a.temperatures, b.temperatures)
    assert a.temperature_names == b.temperature_names


def _info(path, capsys, *args):
    code = main(["-q", "info", str(path), "--json", "-", *args])
    out, err = capsys.readouterr()
    return code, (json.loads(out) if code == 0 else None), err


# -- separators and decimal marks --------------------------------------------------------
@pytest.mark.parametrize(("sep", "decimal"), [(";", ","), (";", "."), ("\t", ","), ("\t", ".")])
def test_european_and_tab_files_read_as_they_are(reference, tmp_path, sep, decimal, capsys):
    """Before: ';' gave "no column 'time' ... the file has ['time;output;...']", decimal
    commas "2 field(s) where the header has 1"."""
    path = _rewrite(reference, tmp_path / "lab.csv", sep=sep, decimal=decimal)
    _same(fogbayes.load(path), fogbayes.load(reference))
    code, doc, err = _info(path, capsys)
    assert code == 0, err
    assert doc["n"] == 3600 and doc["sample_rate_hz"] == pytest.approx(1.0)


def test_given_separator_and_decimal_mark_are_used(reference, tmp_path, capsys):
    path = _rewrite(reference, tmp_path / "lab.csv", sep=";", decimal=",")
    _same(fogbayes.load(path, delimiter=";", decimal=","), fogbayes.load(reference))
    code, _, err = _info(path, capsys, "--delimiter", ";", "--decimal", ",")
    assert code == 0, err


def _one_line_naming(err: str, option: str) -> str:
    """The error as one line whose fix names ``option`` (with its value)."""
    line = err.strip()
    assert "\n" not in line and line.startswith("fogbayes: error:"), err
    assert option in line.split("Fix:", 1)[1], line
    return line


def test_ambiguous_separator_names_the_option_which_then_works(tmp_path, capsys):
    """',' and ';' both split the header and every row alike (a column named 'T,degC',
    decimal commas): no guess, the error names --delimiter ';', which then reads it."""
    rows = [f"{k};{k % 3},{k % 7};20" for k in range(600)]
    path = tmp_path / "two.csv"
    path.write_text("time;output;T,degC\n" + "\n".join(rows) + "\n")
    code, _, err = _info(path, capsys)
    assert code == 2
    assert "two.csv" in _one_line_naming(err, "--delimiter ';'")
    code, doc, err = _info(path, capsys, "--delimiter", ";")
    assert code == 0, err
    rec = fogbayes.load(path, delimiter=";")
    np.testing.assert_array_equal(rec.output, [float(f"{k % 3}.{k % 7}") for k in range(600)])
    assert doc["output_mean"] == pytest.approx(np.mean(rec.output), rel=1e-12)


def test_mixed_decimal_marks_name_the_decimal_option(reference, tmp_path, capsys):
    """One time stamp written '0.0' among decimal commas: which mark is meant is unknown."""
    path = _rewrite(reference, tmp_path / "mixed.csv", sep=";", decimal=",")
    lines = path.read_text().splitlines()
    h = next(i for i, ln in enumerate(lines) if not ln.startswith("#"))
    cells = lines[h + 1].split(";")
    cells[0] = "0.0"
    lines[h + 1] = ";".join(cells)
    path.write_text("\n".join(lines) + "\n")
    code, _, err = _info(path, capsys)
    assert code == 2
    _one_line_naming(err, "--decimal ','")


def test_wrong_separator_given_names_the_right_one(reference, tmp_path, capsys):
    """A ';' file read with --delimiter ',': the header is one field; the fix names ';'."""
    path = _rewrite(reference, tmp_path / "semi.csv", sep=";", decimal=".")
    code, _, err = _info(path, capsys, "--delimiter", ",")
    assert code == 2
    _one_line_naming(err, "--delimiter ';'")
    path = _rewrite(reference, tmp_path / "eu.csv", sep=";", decimal=",")
    code, _, err = _info(path, capsys, "--delimiter", ",")
    assert code == 2
    _one_line_naming(err, "--delimiter ';'")


def test_decimal_comma_with_comma_separator_is_refused(reference, tmp_path, capsys):
    code, _, err = _info(reference, capsys, "--decimal", ",")
    assert code == 2
    _one_line_naming(err, "--delimiter ';'")


def test_decimal_point_forced_on_decimal_commas_names_decimal(reference, tmp_path, capsys):
    path = _rewrite(reference, tmp_path / "eu.csv", sep=";", decimal=",")
    code, _, err = _info(path, capsys, "--decimal", ".")
    assert code == 2
    _one_line_naming(err, "--decimal ','")


def test_csv_options_refused_for_other_formats(reference, tmp_path, capsys):
    npz = tmp_path / "ref.npz"
    fogbayes.save(fogbayes.load(reference), npz)
    code, _, err = _info(npz, capsys, "--delimiter", ";")
    assert code == 2 and "--delimiter" in err and "CSV" in err


# -- time units ---------------------------------------------------------------------------
def test_plain_time_in_ms_gets_a_time_unit_hint_in_info(reference, tmp_path, capsys):
    """Before: "3600 samples, 1e+03 h at 0.001 Hz", exit 0, nothing else."""
    path = _rewrite(reference, tmp_path / "ms.csv", time_factor=1e3, drop_rate=True)
    code, doc, err = _info(path, capsys)
    assert code == 0, err
    assert doc["sample_rate_hz"] == pytest.approx(1e-3)  # read as told: seconds
    assert len(doc["hints"]) == 1 and "--time-unit ms gives 1 Hz" in doc["hints"][0]
    assert main(["-q", "info", str(path)]) == 0
    text = capsys.readouterr().out
    assert "hint:" in text and "--time-unit ms" in text
    code, doc, err = _info(path, capsys, "--time-unit", "ms")
    assert code == 0 and doc["hints"] == [] and doc["sample_rate_hz"] == pytest.approx(1.0)
    _same(fogbayes.load(path, time_unit="ms"), fogbayes.load(reference))


def test_seconds_at_one_hertz_get_no_hint(reference, capsys):
    code, doc, err = _info(reference, capsys)
    assert code == 0 and doc["hints"] == [] and "time_read" not in doc


@pytest.mark.parametrize("model", ["thermal", "bias-t"])
def test_fit_errors_from_a_ms_time_column_name_time_unit(reference, tmp_path, capsys, model):
    """Before: "window_s=60 s is shorter than the sample interval 1000 s. Fix: use
    window_s >= 1000 s" -- no flag; the fix is --time-unit ms, which then fits."""
    path = _rewrite(reference, tmp_path / "ms.csv", time_factor=1e3, drop_rate=True)
    out = tmp_path / "f.json"
    code = main(["-q", "fit", str(path), "-m", model, "--json", str(out)])
    err = capsys.readouterr().err
    assert code == 2
    line = _one_line_naming(err, "--time-unit ms")
    assert "window_s" in line  # the error it explains is still said
    code = main(["-q", "fit", str(path), "-m", model, "--json", str(out), "--time-unit", "ms"])
    assert code == 0, capsys.readouterr().err
    assert json.loads(out.read_text())["model"] == model


@pytest.mark.parametrize(("name", "factor", "unit"),
                         [("time_ms", 1e3, "ms"), ("time [ms]", 1e3, "ms"),
                          ("time (us)", 1e6, "us"), ("t_us", 1e6, "us"),
                          ("timestamp_ns", 1e9, "ns")])
def test_a_unit_in_the_time_column_name_is_read_and_said(reference, tmp_path, capsys, name,
                                                         factor, unit):
    """Before: "no column 'time' ... did you mean 'time_ms'?" (and with --time-column, the
    times read as seconds)."""
    path = _rewrite(reference, tmp_path / "named.csv", time_factor=factor, time_name=name,
                    drop_rate=True)
    rec = fogbayes.load(path)
    np.testing.assert_allclose(rec.time, fogbayes.load(reference).time, rtol=1e-15, atol=1e-12)
    assert unit in rec.meta.extra["time_read"] and name in rec.meta.extra["time_read"]
    code, doc, err = _info(path, capsys)
    assert code == 0, err
    assert doc["sample_rate_hz"] == pytest.approx(1.0) and name in doc["time_read"]
    assert main(["-q", "info", str(path), "--time-column", name]) == 0
    assert f"in {unit}" in capsys.readouterr().out
    # the option overrides the name; saving writes seconds under 'time' and no note
    code, doc, err = _info(path, capsys, "--time-unit", "s")
    if factor == 1e3:
        assert code == 0 and doc["sample_rate_hz"] == pytest.approx(1 / factor)
    else:  # 1e-6 Hz and below: outside the plausible rates, refused naming the unit
        assert code == 2 and "--time-unit" in err.split("Fix:")[1]
    fogbayes.save(rec, tmp_path / "back.csv")
    back = fogbayes.load(tmp_path / "back.csv")
    assert "time_read" not in back.meta.extra
    np.testing.assert_array_equal(back.time, rec.time)


def test_fit_says_how_it_read_a_named_time_column(reference, tmp_path, capsys):
    path = _rewrite(reference, tmp_path / "named.csv", time_factor=1e3, time_name="time_ms",
                    drop_rate=True)
    code = main(["fit", str(path), "-m", "bias-t", "--json", str(tmp_path / "f.json")])
    err = capsys.readouterr().err
    assert code == 0, err
    assert "'time_ms' in ms" in err
