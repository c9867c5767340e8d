"""Hostile input: reading recordings and arguments never gives silently wrong data or a
traceback. Every case runs the command line in-process (``fogbayes.cli.main``) and checks
exit code 2 with exactly one stderr line ``fogbayes: error: ...`` naming the file (and, for
a CSV row, its true physical line: metadata, header and blank lines counted).
"""

from __future__ import annotations

import io
import json
import math
import zipfile

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from fogbayes import load
from fogbayes.cli import main
from fogbayes.simulate import simulate


def run(capsys, *args) -> tuple[int, str, str]:
    capsys.readouterr()
    rc = main([str(a) for a in args])
    cap = capsys.readouterr()
    return rc, cap.out, cap.err


def one_error(capsys, args, *, names=None, contains=(), line=None) -> str:
    """Run ``args``; assert exit 2 and one 'fogbayes: error:' line naming ``names``."""
    rc, _, err = run(capsys, *args)
    lines = err.strip().splitlines()
    assert rc == 2, err
    assert len(lines) == 1 and lines[0].startswith("fogbayes: error: "), err
    msg = lines[0]
    if names is not None:
        assert str(names) in msg, msg
    for text in contains:
        assert text in msg, msg
    if line is not None:
        assert f"(line {line})" in msg or f"line {line}:" in msg, msg
    return msg


# -- CSV files ---------------------------------------------------------------------------
GOOD_ROWS = "0,1.0,20\n1,1.1,20.1\n2,0.9,20.2\n3,1.0,20.3\n"
CSV_CASES = {
    # id: (file text, extra args, texts the message must hold, physical line or None)
    "duplicate column": ("time,output,output\n0,1,2\n1,2,3\n", [],
                         ["two columns are named 'output'", "fields 2 and 3"], 1),
    "extra field": ("time,output\n0,1\n1,2,3\n2,3\n", [], ["row 1", "3 field(s)"], 3),
    "quoted, extra field": ('"time","gyro, x"\n0,"1"\n\n1,"2",3\n', [], ["row 1"], 4),
    "missing field": ("time,output,temperature\n0,1,20\n1,2\n2,3,20\n", [],
                      ["row 1", "2 field(s)"], 3),
    "extra field after metadata and blank lines": (
        "# unit: deg/h\n# sensor_id: s1\n\ntime,output\n0,1\n\n1,2,3\n", [], ["row 1"], 7),
    "text cell after metadata": ("# unit: deg/h\n# sample_rate: 1\ntime,output\n0,1\n\n\n1,abc\n",
                                 [], ["'abc' is not a number", "row 1"], 7),
    "empty cell after metadata": ("# sample_rate: 1\ntime,output\n0,1\n1,\n", [],
                                  ["NaN, empty or infinite", "row 1"], 4),
    "time repeats after blank lines": ("\n\ntime,output\n0,1\n1,2\n1,3\n", [],
                                       ["time repeats", "row 2"], 6),
    "sample_rate not a number": ("# unit: deg/h\n# sample_rate: ten Hz\ntime,output\n" + "0,1\n1,2\n",
                                 [], ["metadata 'sample_rate'", "'ten Hz'"], 2),
    "sample_rate zero": ("# sample_rate: 0\ntime,output\n0,1\n1,2\n", [],
                         ["metadata 'sample_rate'", "> 0"], 1),
    "sample_rate negative": ("# sample_rate: -10\ntime,output\n0,1\n1,2\n", [],
                             ["metadata 'sample_rate'"], 1),
    "scale_factor not a number": ("# unit: V\n# scale_factor: abc\ntime,output\n0,1\n1,2\n", [],
                                  ["metadata 'scale_factor'"], 2),
    "scale_factor zero": ("# unit: V\n# scale_factor: 0\ntime,output\n0,1\n1,2\n", [],
                          ["metadata 'scale_factor'"], 2),
    "unknown unit": ("# unit: furlongs/fortnight\ntime,output\n0,1\n1,2\n", [],
                     ["unknown output unit 'furlongs/fortnight'", "--output-unit"], 1),
    "metadata key twice": ("# unit: deg/h\n# unit: deg/s\ntime,output\n0,1\n1,2\n", [],
                           ["given twice"], 2),
    "metadata after the header": ("time,output\n0,1\n# unit: deg/s\n1,2\n", [],
                                  ["'#' line after the header"], 3),
    "sample_rate disagrees with time": ("# sample_rate: 100\ntime,output\n0,1\n1,2\n2,3\n", [],
                                        ["metadata 'sample_rate' is 100 Hz"], 1),
    "raw temperature words": ("time,output,temperature\n0,1,65236\n1,2,65233\n", [],
                              ["outside -100 ... 200 deg C", "--temperature-scale"], 2),
    "kelvin": ("time,output,temperature\n0,1,20\n1,2,293.15\n", [],
               ["column 'temperature'", "row 1", "-273.15"], 3),
    "time in ns read as s": ("time,output\n0,1\n1000000,2\n2000000,3\n", [],
                             ["sample rate of 1e-06 Hz", "--time-unit"], None),
    "time far too fine": ("time,output\n0,1\n1e-9,2\n2e-9,3\n", [],
                          ["sample rate of 1e+09 Hz", "--time-unit"], None),
    "true/false column": ("time,output\n0,true\n1,false\n", [], ["true/false"], None),
    "unknown time unit": ("time,output\n0,1\n1,2\n", ["--time-unit", "min"],
                          ["unknown time unit 'min'", "s, ms, us or ns"], None),
    "temperature scale zero": (GOOD_ROWS.join(["time,output,temperature\n", ""]),
                               ["--temperature-scale", "0"], ["--temperature-scale"], None),
    "scale factor argument negative": ("time,output\n0,1\n1,2\n", ["--scale-factor", "-2"],
                                       ["--scale-factor"], None),
}


@pytest.mark.parametrize("case", list(CSV_CASES))
def test_bad_csv_is_one_line_naming_file_and_line(tmp_path, capsys, case):
    text, extra, contains, line = CSV_CASES[case]
    p = tmp_path / "rec.csv"
    p.write_text(text, encoding="utf-8")
    named = None if extra and extra[0] in ("--time-unit", "--temperature-scale",
                                           "--scale-factor") else p
    one_error(capsys, ["info", p, *extra], names=named, contains=contains, line=line)


@pytest.mark.parametrize("raw,what", [
    (b"time,output\n0,1\n1,\xff\xfe\n", "not UTF-8"),
    (b"time,output\n0,1\n1,2\x00\x00\n", "NUL bytes"),
])
def test_binary_junk_in_a_csv(tmp_path, capsys, raw, what):
    p = tmp_path / "junk.csv"
    p.write_bytes(raw)
    one_error(capsys, ["info", p], names=p, contains=[what], line=3)


def test_blank_lines_and_metadata_do_not_shift_rows(tmp_path, capsys):
    """A file with metadata and blank lines loads exactly its data rows, metadata checked."""
    p = tmp_path / "ok.csv"
    p.write_text("\ufeff# unit: deg/s\n# sample_rate: 1.0\n# note without a colon\n\n"
                 "time, output ,temperature\n\n" + GOOD_ROWS + "\n  \n", encoding="utf-8")
    rec = load(p)
    assert rec.n == 4 and rec.unit == "deg/s" and rec.meta.sample_rate == 1.0
    assert rec.output.tolist() == [1.0, 1.1, 0.9, 1.0]


def test_time_unit_scales_time(tmp_path):
    p = tmp_path / "ms.csv"
    p.write_text("time (ms),output\n15352,1\n15372,2\n15392,3\n")
    rec = load(p, time="time (ms)", time_unit="ms")
    assert rec.time.tolist() == [15.352, 15.372, 15.392]
    assert rec.sample_rate == pytest.approx(50.0)


# -- NPZ files ---------------------------------------------------------------------------
T, Y = np.arange(10.0), np.full(10, 1.5)


def _npz_bytes(**arrays) -> bytes:
    buf = io.BytesIO()
    np.savez(buf, **arrays)
    return buf.getvalue()


def _bad_crc() -> bytes:
    b = bytearray(_npz_bytes(time=T, output=Y))
    i = b.find(Y.tobytes())
    b[i + 3] ^= 0xFF
    return bytes(b)


def _huge_header() -> bytes:
    """A time array whose header claims 1e15 rows over 80 bytes of data."""
    hdr = io.BytesIO()
    np.lib.format.write_array_header_1_0(hdr, {"descr": "<f8", "fortran_order": False,
                                               "shape": (10**15,)})
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as zf:
        zf.writestr("time.npy", hdr.getvalue() + T.tobytes())
        out = io.BytesIO()
        np.save(out, Y)
        zf.writestr("output.npy", out.getvalue())
    return buf.getvalue()


NPZ_CASES = {
    "bad CRC": (_bad_crc, ["Bad CRC"]),
    "truncated": (lambda: _npz_bytes(time=T, output=Y)[:300], ["cannot read as NPZ"]),
    "not a zip": (lambda: b"time,output\n0,1\n", ["cannot read as NPZ"]),
    "unequal columns": (lambda: _npz_bytes(time=T, output=Y[:9]), ["9 rows", "'time' has 10"]),
    "header claims 1e15 rows": (_huge_header, ["declares shape (1000000000000000,)"]),
    "object array": (lambda: _npz_bytes(time=T.astype(object), output=Y), ["Python objects"]),
    "string array": (lambda: _npz_bytes(time=T.astype(str), output=Y), ["not real numbers"]),
    "complex array": (lambda: _npz_bytes(time=T, output=Y + 1j), ["not real numbers"]),
    "2-D array": (lambda: _npz_bytes(time=T, output=np.ones((10, 2))), ["expected 1-D"]),
    "meta not JSON": (lambda: _npz_bytes(time=T, output=Y, __meta__=np.array("{unit: deg/h")),
                      ["'__meta__' array is not JSON"]),
    "meta not an object": (lambda: _npz_bytes(time=T, output=Y, __meta__=np.array("[1, 2]")),
                           ["not an object"]),
    "meta sample_rate text": (
        lambda: _npz_bytes(time=T, output=Y, __meta__=np.array('{"sample_rate": "fast"}')),
        ["metadata 'sample_rate'"]),
    "meta unit a list": (
        lambda: _npz_bytes(time=T, output=Y, __meta__=np.array('{"unit": ["deg/h"]}')),
        ["metadata 'unit'"]),
}


@pytest.mark.parametrize("case", list(NPZ_CASES))
def test_damaged_npz_is_one_line_naming_the_file(tmp_path, capsys, case):
    make, contains = NPZ_CASES[case]
    p = tmp_path / "rec.npz"
    p.write_bytes(make())
    one_error(capsys, ["info", p], names=p, contains=contains)


# -- Parquet files -----------------------------------------------------------------------
def _parquet(path, table=None, meta: bytes | None = None):
    table = table if table is not None else pa.table({"time": T, "output": Y})
    if meta is not None:
        table = table.replace_schema_metadata({b"fogbayes": meta})
    pq.write_table(table, path)


def _truncated(path):
    _parquet(path)
    path.write_bytes(path.read_bytes()[:200])


PARQUET_CASES = {
    "truncated": (_truncated, ["cannot read as Parquet"]),
    "not parquet": (lambda p: p.write_text("time,output\n0,1\n"), ["cannot read as Parquet"]),
    "duplicate column": (lambda p: _parquet(p, pa.Table.from_arrays(
        [pa.array(T), pa.array(Y), pa.array(Y)], names=["time", "output", "output"])),
        ["two columns are named 'output'", "positions 2 and 3"]),
    "meta not JSON": (lambda p: _parquet(p, meta=b"{bad"), ["not JSON"]),
    "meta wrong type": (lambda p: _parquet(p, meta=b'{"sample_rate": [1]}'),
                        ["metadata 'sample_rate'"]),
    "meta scale factor negative": (lambda p: _parquet(p, meta=b'{"unit": "V", "scale_factor": -2}'),
                                   ["metadata 'scale_factor'"]),
}


@pytest.mark.parametrize("case", list(PARQUET_CASES))
def test_damaged_parquet_is_one_line_naming_the_file(tmp_path, capsys, case):
    make, contains = PARQUET_CASES[case]
    p = tmp_path / "rec.parquet"
    make(p)
    one_error(capsys, ["info", p], names=p, contains=contains)


# -- arguments and analyses ----------------------------------------------------------------
@pytest.fixture(scope="module")
def small(tmp_path_factory):
    """A 600 s thermal recording at 1 Hz (CSV) and its first 40 rows."""
    from fogbayes import save

    d = tmp_path_factory.mktemp("hostile")
    rec = simulate("thermal", seed=0, duration=600.0, fs=1.0).recording
    return save(rec, d / "small.csv"), save(rec.slice(0, 40), d / "short40.csv"), d


ARG_CASES = {
    "simulate --fs 0": (["simulate", "--fs", "0", "--out", "{d}/s.csv"], ["--fs"]),
    "simulate --duration 0": (["simulate", "--duration", "0", "--out", "{d}/s.csv"],
                              ["--duration"]),
    "simulate --duration 1e12": (["simulate", "--duration", "1e12", "--out", "{d}/s.csv"],
                                 ["1e+13 samples", "GB per column"]),
    "simulate --fs 1e9": (["simulate", "--fs", "1e9", "--out", "{d}/s.csv"], ["samples"]),
    "simulate bad --effect JSON": (["simulate", "--effect", "step={size: 1", "--out",
                                    "{d}/s.csv"], ["--effect", "not valid JSON"]),
    "simulate --effect wrong type": (["simulate", "--effect", 'step={"size": "big"}', "--out",
                                      "{d}/s.csv"], ["size='big' is not a finite number"]),
    "arma --lags -1": (["arma", "{small}", "--json", "-", "--lags", "-1"], ["--lags"]),
    "fit -O n_sigma=abc": (["fit", "{small}", "-m", "thermal", "--json", "-", "-O",
                            "n_sigma=abc"], ["n_sigma must be a number > 0"]),
    "fit -O num_samples=1.5": (["fit", "{small}", "-m", "thermal", "--json", "-", "-O",
                                "num_samples=1.5"], ["num_samples must be an integer >= 1"]),
    "fit -m arma -O foo=1": (["fit", "{small}", "-m", "arma", "--json", "-", "-O", "foo=1"],
                             ["unknown option 'foo'"]),
    "allan --plot a.xyz": (["allan", "{small}", "--json", "-", "--plot", "{d}/a.xyz"],
                           ["'.xyz'", ".png", ".pdf"]),
}


@pytest.mark.parametrize("case", list(ARG_CASES))
def test_bad_arguments_are_one_line(small, capsys, case):
    path, _, d = small
    args, contains = ARG_CASES[case]
    args = [a.replace("{small}", str(path)).replace("{d}", str(d)) for a in args]
    one_error(capsys, args, contains=contains)
    assert not (d / "s.csv").exists()


def test_loop_on_40_rows_is_too_short(small, capsys):
    _, short, d = small
    one_error(capsys, ["loop", short, "-m", "bias-t", "--json", "-", "--compensated",
                       d / "c.csv"], names=short, contains=["at least 100 samples"])


def test_too_short_and_unit_errors_name_the_file(small, capsys, tmp_path):
    _, short, _ = small
    one_error(capsys, ["allan", short, "--json", "-"], names=short, contains=["octave taus"])
    volts = tmp_path / "volts.csv"
    volts.write_text("# unit: V\ntime,output\n" + "".join(f"{k},{0.1 * k}\n" for k in range(400)))
    one_error(capsys, ["allan", volts, "--json", "-"], names=volts, contains=["scale factor"])


def test_mathtext_in_a_sensor_id_does_not_crash_the_report(small, capsys, tmp_path):
    path, _, _ = small
    text = path.read_text().replace("# sensor_id: sim-thermal-0", "# sensor_id: $\\alpha^{$")
    text = text.replace("temperature_2", "temp $x^{$", 1)
    p = tmp_path / "mathtext.csv"
    p.write_text(text)
    rc, _, err = run(capsys, "-q", "report", p, "--temperature", "temperature",
                     "--temperature", "temp $x^{$", "--out", tmp_path / "r.html")
    assert rc == 0, err
    assert "$\\alpha^{$" in (tmp_path / "r.html").read_text()


# -- the PAN TVAC measured file through the command line ------------------------------------
PAN = ("pan_lsm6dsm_tvac_cold", "TVCtest3_7_20.csv")
#: SOURCE.md's recipe as options: time in ms; temp = int16(raw)/256 + 25 deg C, which for
#: these words (all >= 32768) is raw/256 - 231; the file's gyro is 2x the rate in rad/s,
#: i.e. a raw output of 2 x pi/180 units per deg/s.
PAN_ARGS = ["--time-column", "time (ms)", "--time-unit", "ms", "--column", "gyrox rad/s",
            "--temperature", "temp", "--temperature-scale", "0.00390625",
            "--temperature-offset", "-231", "--output-unit", "V",
            "--scale-factor", repr(2 * math.pi / 180)]


@pytest.mark.measured
def test_pan_tvac_file_loads_through_the_cli_like_the_recipe(measured, capsys):
    from fogbayes.thermal.pan_tvac import load_pan_tvac

    path = measured(*PAN)
    rc, out, err = run(capsys, "info", path, *PAN_ARGS, "--json", "-")
    assert rc == 0, err
    doc = json.loads(out)
    assert doc["n"] == 6250 and doc["sample_rate_hz"] == pytest.approx(50.0, rel=0.05)
    assert doc["temperatures"]["temp"]["min"] == pytest.approx(15.57, abs=0.01)
    assert doc["temperatures"]["temp"]["max"] == pytest.approx(23.88, abs=0.01)
    rec = load(path, time="time (ms)", time_unit="ms", output="gyrox rad/s", temperature="temp",
               temperature_scale=1 / 256, temperature_offset=-231.0, unit="V",
               scale_factor=2 * math.pi / 180)
    ref = load_pan_tvac(path, "x")
    np.testing.assert_array_equal(rec.time, ref.time)
    np.testing.assert_array_equal(rec.temperature, ref.temperature)
    np.testing.assert_allclose(rec.rate("deg/h"), ref.rate("deg/h"), rtol=1e-12)
    # without the temperature scale: refused, naming the column and the options to use
    one_error(capsys, ["info", path, *PAN_ARGS[:8]], names=path,
              contains=["column 'temp'", "65236", "--temperature-scale"], line=2)


# -- property: mutated small CSV files -------------------------------------------------------
BASE = ["# unit: deg/h", "# sensor_id: fog-1", "# sample_rate: 1.0", "time,output,temperature"]
BASE += [f"{k},{0.1 * k:.3f},{20 + 0.5 * k:.2f}" for k in range(8)]


@st.composite
def mutated(draw) -> list[str]:
    lines = list(BASE)
    for _ in range(draw(st.integers(1, 2))):
        kind = draw(st.sampled_from(["cell", "duplicate", "delete", "field", "header",
                                     "metadata", "blank"]))
        i = draw(st.integers(0, len(lines) - 1))
        if kind == "cell" and "," in lines[i]:
            cells = lines[i].split(",")
            j = draw(st.integers(0, len(cells) - 1))
            cells[j] = draw(st.sampled_from(["abc", "nan", "", "1e400", " 7 ", "--", "1,5"]))
            lines[i] = ",".join(cells)
        elif kind == "duplicate":
            lines.insert(i, lines[i])
        elif kind == "delete" and len(lines) > 1:
            del lines[i]
        elif kind == "field":
            lines[i] += "," + draw(st.sampled_from(["0", "", "x"]))
        elif kind == "header":
            h = lines.index("time,output,temperature") if "time,output,temperature" in lines else i
            lines[h] = draw(st.sampled_from(["time,output,output", "time,outptu,temperature",
                                             "time,output,temperature,", "t,output,temperature",
                                             "time;output;temperature"]))
        elif kind == "metadata":
            lines[draw(st.integers(0, 2))] = draw(st.sampled_from([
                "# sample_rate: ten Hz", "# sample_rate: -1", "# unit: furlongs",
                "# scale_factor: x", "# sample_rate", "#: 5", "# sample_rate: 1e400",
                "# unit: deg/s"]))
        else:
            lines.insert(i, draw(st.sampled_from(["", "   ", "\t"])))
    return lines


def _data_lines(lines: list[str]) -> int:
    """Rows a reader must return: non-blank lines after the first non-'#' line."""
    body = [ln for ln in lines if ln.strip()]
    for k, ln in enumerate(body):
        if not ln.lstrip().startswith("#"):
            return len(body) - k - 1
    return 0


@settings(max_examples=40, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(lines=mutated())
def test_mutated_csv_is_read_exactly_or_refused_in_one_line(tmp_path, capsys, lines):
    p = tmp_path / "mutated.csv"
    p.write_text("\n".join(lines) + "\n", encoding="utf-8")
    rc, out, err = run(capsys, "info", p, "--json", "-")
    assert rc in (0, 2), err
    if rc == 2:
        err_lines = err.strip().splitlines()
        assert len(err_lines) == 1 and err_lines[0].startswith("fogbayes: error: "), err
        assert str(p) in err_lines[0]
    else:
        assert json.loads(out)["n"] == _data_lines(lines)
