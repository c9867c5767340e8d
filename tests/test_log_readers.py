"""Gyro logs read directly (fogbayes/data/logs, docs/logs.md): PX4 ULog, ROS 1 bag, ROS 2 bag
(sqlite3 and MCAP storage, folder or single file), bare MCAP, ArduPilot DataFlash.

Small logs with known rates (a sine, a constant, a ramp, plus noise) and a temperature ramp
are written (tests/_log_writers.py: with rosbags and mcap where they write the format, by
hand from the format specifications for ULog and DataFlash) and read back through
fogbayes.load, which uses the libraries: what is read must be what was written (float32
where the format stores float32), in rad/s, with the topic/instance asked for. Bad logs
are one FogbayesError naming the file.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys

import numpy as np
import pytest

import _log_writers as W
import fogbayes
from fogbayes.cli import main
from fogbayes.data.logs import LOG_SUFFIXES, is_log, read_log
from fogbayes.errors import (ArgumentError, FileFormatError, FogbayesError, MissingExtraError,
                             TimeOrderError, UnitError)

# the test extra installs the log libraries: in CI a missing one is a failure, not a skip
for _lib in ("rosbags", "pyulog", "pymavlink", "mcap"):
    if os.environ.get("CI"):
        __import__(_lib)
    else:
        pytest.importorskip(_lib)

S = W.series()  # instance 0 / the IMU topic
S2 = W.series(offset=0.5, seed=1)  # instance 1 / a second IMU topic
AXES = "xyz"


def f32(a):
    return np.asarray(a, dtype=np.float32).astype(np.float64)


def ros_time(s: W.Series) -> np.ndarray:
    """Header stamps as fogbayes reads them: sec + nanosec * 1e-9."""
    return (s.t_ns // 10**9).astype(np.float64) + (s.t_ns % 10**9).astype(np.float64) * 1e-9


@pytest.fixture(scope="module")
def logs(tmp_path_factory):
    d = tmp_path_factory.mktemp("logs")
    imu, temp = {"/imu/data": S}, {"/imu/temperature": S}
    return {
        "ros1": W.write_ros1(d / "run.bag", imu, temp),
        "ros2-sqlite3": W.write_ros2(d / "run_db3", imu, temp),
        "ros2-mcap": W.write_ros2(d / "run_mcap", imu, temp, storage="mcap"),
        "mcap": W.write_mcap(d / "run.mcap", imu, temp),
        "ulog": W.write_ulog(d / "flight.ulg", {("sensor_gyro", 0): S, ("sensor_gyro", 1): S2,
                                                ("sensor_accel", 0): S}),
        "df": W.write_dataflash(d / "00000001.BIN", {0: S, 1: S2}),
        "df-old": W.write_dataflash(d / "old.bin", {0: S, 1: S2}, old_style=True),
        "dir": d,
    }


# -- ROS -------------------------------------------------------------------------------
@pytest.mark.parametrize("kind", ["ros1", "ros2-sqlite3", "ros2-mcap", "mcap", "db3-file"])
def test_ros_logs_read_back_what_was_written(logs, kind):
    path = next(logs["ros2-sqlite3"].glob("*.db3")) if kind == "db3-file" else logs[kind]
    assert is_log(path)
    table = read_log(path)
    np.testing.assert_array_equal(table.columns["time"], ros_time(S))
    for j, a in enumerate(AXES):  # float64 on the wire: exact
        np.testing.assert_array_equal(table.columns[f"gyro_{a}"], S.gyro[:, j])
    rec = fogbayes.load(path, axis="z")
    assert rec.unit == "rad/s" and rec.n == len(S.t_ns)
    np.testing.assert_array_equal(rec.time, ros_time(S))
    np.testing.assert_array_equal(rec.output, S.gyro[:, 2])
    np.testing.assert_array_equal(rec.temperature, S.temperature)  # same stamps: exact
    extra = rec.meta.extra
    assert extra["log_topic"] == "/imu/data" and extra["axis"] == "z"
    assert extra["temperature_topic"] == "/imu/temperature"
    assert extra["temperature_held_start"] == extra["temperature_held_end"] == 0
    assert rec.meta.sensor_id.endswith(":/imu/data")


def test_ros_temperature_is_interpolated_and_held_at_the_ends(tmp_path):
    # 10 Hz temperature from 12.35 s to 14.25 s under a 100 Hz gyro from 12 s to 14.99 s
    temp = W.series(n=20, fs=10.0, start_s=12.35)
    path = W.write_ros2(tmp_path / "bag", {"/imu": S}, {"/t": temp})
    rec = fogbayes.load(path)
    t = rec.time
    first, last = temp.t_ns[0] / 1e9, temp.t_ns[-1] / 1e9
    # the written ramp is 25 + 0.05 (t - first): linear, so interpolation gives it exactly
    expected = 25.0 + 0.05 * (np.clip(t, first, last) - first)
    np.testing.assert_allclose(rec.temperature, expected, rtol=0, atol=1e-9)
    extra = rec.meta.extra
    assert extra["temperature_held_start"] == int(np.sum(t < first)) == 35
    assert extra["temperature_held_end"] == int(np.sum(t > last)) == 74
    assert "no extrapolation" in extra["temperature_alignment"]


def test_ros_topic_selection(tmp_path):
    path = W.write_ros1(tmp_path / "two.bag", {"/imu0": S, "/imu1": S2},
                        {"/imu0/temp": S, "/imu1/temp": S2})
    with pytest.raises(FogbayesError, match=r"2 sensor_msgs/msg/Imu topics.*/imu0.*/imu1") as e:
        fogbayes.load(path)
    assert str(path) in str(e.value) and "--topic" in str(e.value)
    with pytest.raises(FogbayesError, match=r"2 sensor_msgs/msg/Temperature topics"):
        fogbayes.load(path, topic="/imu1")
    rec = fogbayes.load(path, topic="/imu1,/imu1/temp", axis="y")
    np.testing.assert_array_equal(rec.output, S2.gyro[:, 1])
    np.testing.assert_array_equal(rec.temperature, S2.temperature)
    with pytest.raises(FogbayesError, match=r"'/nope' is not in the bag.*/imu0") as e:
        fogbayes.load(path, topic="/nope")
    assert str(path) in str(e.value)
    with pytest.raises(FogbayesError, match="is a sensor_msgs/msg/Temperature topic"):
        fogbayes.load(path, topic="/imu0/temp")
    with pytest.raises(FogbayesError, match="no sensor instances"):
        fogbayes.load(path, topic="/imu0,/imu0/temp", instance=1)


def test_ros_bag_without_imu_names_what_it_has(tmp_path):
    path = W.write_ros2(tmp_path / "temps_only", {}, {"/t": S})
    with pytest.raises(FogbayesError, match=r"no sensor_msgs/msg/Imu topic.*/t \(") as e:
        fogbayes.load(path)
    assert str(path) in str(e.value)


# -- PX4 ULog --------------------------------------------------------------------------
def test_ulog_sensor_gyro_instances(logs):
    path = logs["ulog"]
    rec = fogbayes.load(path)
    np.testing.assert_array_equal(rec.time, S.t_us / 1e6)  # timestamp_sample, not timestamp
    np.testing.assert_array_equal(rec.output, f32(S.gyro[:, 0]))
    np.testing.assert_array_equal(rec.temperature, f32(S.temperature))
    assert rec.unit == "rad/s" and rec.meta.sensor_id == "flight:sensor_gyro[0]"
    assert rec.meta.extra["time_source"].startswith("sensor_gyro.timestamp_sample")
    for j, a in enumerate(AXES):
        rec = fogbayes.load(path, instance=1, axis=a)
        np.testing.assert_array_equal(rec.output, f32(S2.gyro[:, j]))
        assert rec.meta.extra["log_instance"] == 1 and rec.meta.extra["axis"] == a
    np.testing.assert_array_equal(fogbayes.load(path, output="gyro_y").output, f32(S.gyro[:, 1]))
    with pytest.raises(FogbayesError, match=r"no instance 2; the log has instances \[0, 1\]") as e:
        fogbayes.load(path, instance=2)
    assert str(path) in str(e.value)
    with pytest.raises(FogbayesError, match="not a gyro topic"):
        fogbayes.load(path, topic="sensor_accel")


def test_ulog_falls_back_to_sensor_combined(tmp_path):
    path = W.write_ulog(tmp_path / "default.ulg", {("sensor_combined", 0): S})
    rec = fogbayes.load(path, axis="y")
    np.testing.assert_array_equal(rec.time, S.t_us / 1e6)
    np.testing.assert_array_equal(rec.output, f32(S.gyro[:, 1]))
    assert not rec.has_temperature
    assert rec.meta.extra["log_topic"] == "sensor_combined"
    assert "carries no temperature" in rec.meta.extra["temperature_alignment"]
    with pytest.raises(FogbayesError, match="no 'sensor_gyro' messages"):
        fogbayes.load(path, topic="sensor_gyro")


def test_ulog_without_gyro_and_repeated_or_reversed_stamps(tmp_path):
    path = W.write_ulog(tmp_path / "accel.ulg", {("sensor_accel", 0): S})
    with pytest.raises(FogbayesError, match="no gyro messages") as e:
        fogbayes.load(path)
    assert str(path) in str(e.value)
    # a message logged twice is one sample: removed and counted, not silently
    twice = W.Series(np.insert(S.t_ns, 5, S.t_ns[5]), np.insert(S.gyro, 5, S.gyro[5], axis=0),
                     np.insert(S.temperature, 5, S.temperature[5]))
    rec = fogbayes.load(W.write_ulog(tmp_path / "twice.ulg", {("sensor_gyro", 0): twice}))
    assert rec.n == len(S.t_ns) and rec.meta.extra["repeated_messages_removed"] == 1
    back = W.Series(S.t_ns.copy(), S.gyro, S.temperature)
    back.t_ns[[10, 11]] = back.t_ns[[11, 10]]
    with pytest.raises(TimeOrderError, match="goes back at message 11") as e:
        fogbayes.load(W.write_ulog(tmp_path / "back.ulg", {("sensor_gyro", 0): back}))
    assert "back.ulg" in str(e.value)


# -- ArduPilot DataFlash ---------------------------------------------------------------
@pytest.mark.parametrize("kind", ["df", "df-old"])
def test_dataflash_instances(logs, kind):
    path = logs[kind]
    for k, s in ((0, S), (1, S2)):
        table = read_log(path, instance=k)
        for j, a in enumerate(AXES):
            np.testing.assert_array_equal(table.columns[f"gyro_{a}"], f32(s.gyro[:, j]))
        rec = fogbayes.load(path, instance=k, axis="z")
        np.testing.assert_array_equal(rec.time, S.t_us / 1e6)
        np.testing.assert_array_equal(rec.output, f32(s.gyro[:, 2]))
        np.testing.assert_array_equal(rec.temperature, f32(s.temperature))
        assert rec.unit == "rad/s" and rec.meta.extra["log_instance"] == k
    with pytest.raises(FogbayesError, match="instance 2") as e:
        fogbayes.load(path, instance=2)
    assert str(path) in str(e.value) and "--instance 0" in str(e.value)
    if kind == "df-old":
        assert fogbayes.load(path, topic="IMU2").meta.sensor_id == "old:IMU2[1]"


def test_dataflash_skipped_bytes_are_reported_not_printed(tmp_path, capfd):
    good = W.write_dataflash(tmp_path / "a.bin", {0: S}).read_bytes()
    cut = good.index(b"\xa3\x95", 2000)  # a message boundary in the data
    path = tmp_path / "damaged.bin"
    path.write_bytes(good[:cut] + b"\x00" * 700 + good[cut:])
    rec = fogbayes.load(path)
    assert rec.n == len(S.t_ns)
    assert rec.meta.extra["reader_note_count"] > 0  # pymavlink's notes, kept
    out, err = capfd.readouterr()
    assert out == "" and err == ""


# -- errors common to all formats ------------------------------------------------------
@pytest.mark.parametrize("name", ["junk.ulg", "junk.bag", "junk.mcap", "junk.db3", "junk.bin",
                                  "empty.bin", "empty.ulg"])
def test_damaged_files_are_one_line_naming_the_file(tmp_path, name):
    path = tmp_path / name
    path.write_bytes(b"" if name.startswith("empty") else
                     np.random.default_rng(3).bytes(3000))
    with pytest.raises(FileFormatError) as e:
        fogbayes.load(path)
    msg = str(e.value)
    assert msg.startswith(str(path)) and "\n" not in msg and "Fix:" in msg


@pytest.mark.parametrize("kind, modules", [("ulog", ["pyulog"]),
                                           ("ros1", ["rosbags", "rosbags.highlevel"]),
                                           ("df", ["pymavlink", "pymavlink.DFReader"])])
def test_missing_library_names_the_extra(logs, monkeypatch, kind, modules):
    for name in modules:  # as on an install without the extra
        monkeypatch.setitem(sys.modules, name, None)
    with pytest.raises(MissingExtraError, match=r"need \w+, which is not installed. "
                                                r"Fix: pip install 'fogbayes\[logs\]'"):
        fogbayes.load(logs[kind])


def test_options_that_would_misread_a_log_or_a_csv(logs, tmp_path):
    with pytest.raises(UnitError, match="rad/s"):
        fogbayes.load(logs["ulog"], unit="deg/h")
    with pytest.raises(ArgumentError, match="--time-unit"):
        fogbayes.load(logs["ulog"], time_unit="ms")
    with pytest.raises(ArgumentError, match="disagree"):
        fogbayes.load(logs["ulog"], output="gyro_x", axis="y")
    with pytest.raises(ArgumentError, match="unknown axis"):
        fogbayes.load(logs["ulog"], axis="w")
    csv = tmp_path / "a.csv"
    csv.write_text("time,output\n0,1\n1,2\n")
    with pytest.raises(ArgumentError, match="--axis applies to gyro logs only") as e:
        fogbayes.load(csv, axis="y")
    assert str(csv) in str(e.value)
    with pytest.raises(FileFormatError) as e:
        fogbayes.load(tmp_path / "a.xyz")
    assert all(s in str(e.value) for s in LOG_SUFFIXES)


# -- command line ----------------------------------------------------------------------
def test_cli_allan_on_a_ulog_and_axis_changes_it(logs, tmp_path, capsys):
    out_x, out_y = tmp_path / "x.json", tmp_path / "y.json"
    assert main(["-q", "allan", str(logs["ulog"]), "--json", str(out_x)]) == 0
    assert main(["-q", "allan", str(logs["ulog"]), "--axis", "y", "--json", str(out_y)]) == 0
    doc_x, doc_y = json.loads(out_x.read_text()), json.loads(out_y.read_text())
    assert doc_x["n"] == doc_y["n"] == len(S.t_ns)
    assert doc_x["adev"] != doc_y["adev"]
    assert main(["allan", str(logs["ulog"]), "--instance", "7", "--json", str(out_x)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and str(logs["ulog"]) in err[0] and "instances [0, 1]" in err[0]


def test_the_cli_and_csv_users_import_no_log_library():
    code = ("import sys, fogbayes.cli, fogbayes; fogbayes.load; "
            "print([m for m in sys.modules if m.split('.')[0] in "
            "('pyulog', 'rosbags', 'mcap', 'pymavlink')])")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"
