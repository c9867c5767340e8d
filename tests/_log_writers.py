"""Writers of small gyro logs for tests/test_log_readers.py.

ROS 1 bags, ROS 2 bags (sqlite3 and MCAP storage) and a bare MCAP file are written with the
libraries themselves (``rosbags``' writers; ``mcap``'s writer with messages serialised by
``rosbags``). Neither pyulog nor pymavlink writes a log from scratch (pyulog only writes
back a log it has read; pymavlink only packs single messages on a reader object), so ULog
and DataFlash files are written here byte by byte from the published specifications:

* ULog (docs.px4.io, "ULog File Format"): a 16-byte header (magic ``ULog\\x01\\x12\\x35``,
  version, start time in us), then messages of ``uint16 size, uint8 type, payload``:
  ``B`` flag bits, ``F`` formats ``name:type field;...``, ``A`` subscriptions (multi_id,
  msg_id, name) and ``D`` data (msg_id, the packed fields, timestamp first).
* DataFlash (ArduPilot): messages ``0xA3 0x95 type payload``; type 0x80 is ``FMT``
  (type, length, name[4], format[16], columns[64]) which defines every other type by its
  format characters (``Q`` uint64, ``B`` uint8, ``f`` float, ``I`` uint32, ...).

Every writer takes a :class:`Series` so the tests compare against the values written.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass
from pathlib import Path

import numpy as np


@dataclass
class Series:
    """Known samples: time in integer ns, rates in rad/s, temperature in deg C."""

    t_ns: np.ndarray
    gyro: np.ndarray  # (n, 3)
    temperature: np.ndarray

    @property
    def t_us(self) -> np.ndarray:
        return self.t_ns // 1000


def series(n: int = 300, fs: float = 100.0, start_s: float = 12.0, offset: float = 0.0,
           seed: int = 0) -> Series:
    """x: a sine, y: a constant, z: a slow ramp, each with white noise of its own size (so
    the three axes differ in their Allan deviation); temperature a ramp from 25 deg C."""
    t_ns = (np.int64(start_s * 1e9) + np.arange(n, dtype=np.int64) * np.int64(1e9 / fs))
    t = (t_ns - t_ns[0]) / 1e9
    noise = np.random.default_rng(seed).normal(size=(n, 3)) * [1e-4, 1e-3, 1e-5]
    gyro = np.column_stack([0.01 * np.sin(2 * np.pi * 0.5 * t), np.full(n, 0.002),
                            1e-4 * t - 0.003]) + noise + offset
    return Series(t_ns, gyro, 25.0 + 0.05 * t + offset)


# -- ROS -------------------------------------------------------------------------------
def _stamp(ts, ns: int):
    Time = ts.types["builtin_interfaces/msg/Time"]
    return Time(sec=int(ns // 10**9), nanosec=int(ns % 10**9))


def _header(ts, ns: int, ros1: bool):
    Header = ts.types["std_msgs/msg/Header"]
    if ros1:
        return Header(seq=0, stamp=_stamp(ts, ns), frame_id="imu")
    return Header(stamp=_stamp(ts, ns), frame_id="imu")


def imu_msg(ts, ns: int, w, ros1: bool = False):
    V3 = ts.types["geometry_msgs/msg/Vector3"]
    Q = ts.types["geometry_msgs/msg/Quaternion"]
    Imu = ts.types["sensor_msgs/msg/Imu"]
    cov = np.zeros(9)
    return Imu(header=_header(ts, ns, ros1), orientation=Q(x=0.0, y=0.0, z=0.0, w=1.0),
               orientation_covariance=cov, angular_velocity=V3(x=float(w[0]), y=float(w[1]),
                                                               z=float(w[2])),
               angular_velocity_covariance=cov, linear_acceleration=V3(x=0.0, y=0.0, z=9.81),
               linear_acceleration_covariance=cov)


def temp_msg(ts, ns: int, value: float, ros1: bool = False):
    Temperature = ts.types["sensor_msgs/msg/Temperature"]
    return Temperature(header=_header(ts, ns, ros1), temperature=float(value), variance=0.0)


def _messages(ts, imus: dict[str, Series], temps: dict[str, Series], ros1: bool):
    """(topic, msgtype, ns, message) of every message, in time order."""
    out = []
    for topic, s in imus.items():
        out += [(topic, "sensor_msgs/msg/Imu", int(ns), imu_msg(ts, int(ns), w, ros1))
                for ns, w in zip(s.t_ns, s.gyro)]
    for topic, s in temps.items():
        out += [(topic, "sensor_msgs/msg/Temperature", int(ns), temp_msg(ts, int(ns), v, ros1))
                for ns, v in zip(s.t_ns, s.temperature)]
    return sorted(out, key=lambda m: m[2])


def write_ros1(path: Path, imus: dict, temps: dict | None = None) -> Path:
    from rosbags.rosbag1 import Writer
    from rosbags.typesys import Stores, get_typestore

    ts = get_typestore(Stores.ROS1_NOETIC)
    with Writer(path) as w:
        conns = {}
        for topic, typ, ns, msg in _messages(ts, imus, temps or {}, True):
            if topic not in conns:
                conns[topic] = w.add_connection(topic, typ, typestore=ts)
            w.write(conns[topic], ns, ts.serialize_ros1(msg, typ))
    return path


def write_ros2(path: Path, imus: dict, temps: dict | None = None, storage: str = "sqlite3") -> Path:
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    ts = get_typestore(Stores.ROS2_HUMBLE)
    plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
    with Writer(path, version=9, storage_plugin=plugin) as w:
        conns = {}
        for topic, typ, ns, msg in _messages(ts, imus, temps or {}, False):
            if topic not in conns:
                conns[topic] = w.add_connection(topic, typ, typestore=ts)
            w.write(conns[topic], ns, ts.serialize_cdr(msg, typ))
    return path


def write_mcap(path: Path, imus: dict, temps: dict | None = None) -> Path:
    """A bare MCAP file as ROS 2 tools write it (schema ros2msg, messages cdr), written
    with the ``mcap`` package, not with rosbags."""
    from mcap.writer import Writer
    from rosbags.typesys import Stores, get_typestore

    ts = get_typestore(Stores.ROS2_HUMBLE)
    with open(path, "wb") as fh:
        w = Writer(fh)
        w.start(profile="ros2", library="fogbayes-tests")
        channels = {}
        for topic, typ, ns, msg in _messages(ts, imus, temps or {}, False):
            if topic not in channels:
                schema = w.register_schema(name=typ, encoding="ros2msg",
                                           data=ts.generate_msgdef(typ, ros_version=2)[0].encode())
                channels[topic] = w.register_channel(topic=topic, message_encoding="cdr",
                                                     schema_id=schema)
            w.add_message(channels[topic], log_time=ns, data=bytes(ts.serialize_cdr(msg, typ)),
                          publish_time=ns)
        w.finish()
    return path


# -- PX4 ULog --------------------------------------------------------------------------
_ULOG_FORMATS = {
    "sensor_gyro": ("uint64_t timestamp;uint64_t timestamp_sample;uint32_t device_id;"
                    "float x;float y;float z;float temperature;uint32_t error_count;"),
    "sensor_combined": ("uint64_t timestamp;float[3] gyro_rad;uint32_t gyro_integral_dt;"
                        "int32_t accelerometer_timestamp_relative;float[3] accelerometer_m_s2;"),
    "sensor_accel": "uint64_t timestamp;float x;float y;float z;float temperature;",
}


def _ulog_msg(kind: bytes, payload: bytes) -> bytes:
    return struct.pack("<HB", len(payload), kind[0]) + payload


def _ulog_row(topic: str, s: Series, k: int) -> bytes:
    us = int(s.t_us[k])
    x, y, z = (float(v) for v in s.gyro[k])
    if topic == "sensor_gyro":  # timestamp (publication) after timestamp_sample
        return struct.pack("<QQIffffI", us + 80, us, 1234, x, y, z, float(s.temperature[k]), 0)
    if topic == "sensor_combined":
        return struct.pack("<QfffIifff", us, x, y, z, 4000, 0, 0.0, 0.0, 9.81)
    return struct.pack("<Qffff", us, 0.0, 0.0, 9.81, float(s.temperature[k]))


def write_ulog(path: Path, instances: dict[tuple[str, int], Series],
               params: dict[str, int] | None = None) -> Path:
    """``instances`` maps (topic, multi_id) to the samples of that instance; ``params``:
    int32 parameters ('P' messages: key length, "int32_t NAME", value)."""
    out = b"ULog\x01\x12\x35" + struct.pack("<BQ", 1, 0)
    out += _ulog_msg(b"B", bytes(16) + struct.pack("<3Q", 0, 0, 0))
    for topic in sorted({tp for tp, _ in instances}):
        out += _ulog_msg(b"F", f"{topic}:{_ULOG_FORMATS[topic]}".encode())
    key = b"char[3] sys_name"
    out += _ulog_msg(b"I", bytes([len(key)]) + key + b"PX4")
    for name, value in (params or {}).items():
        pkey = f"int32_t {name}".encode()
        out += _ulog_msg(b"P", bytes([len(pkey)]) + pkey + struct.pack("<i", int(value)))
    rows = []
    for msg_id, ((topic, multi), s) in enumerate(sorted(instances.items())):
        out += _ulog_msg(b"A", struct.pack("<BH", multi, msg_id) + topic.encode())
        rows += [(k, msg_id, _ulog_row(topic, s, k)) for k in range(len(s.t_ns))]
    # interleaved by sample index, each instance in the order given (a test may disorder it)
    out += b"".join(_ulog_msg(b"D", struct.pack("<H", msg_id) + row)
                    for _, msg_id, row in sorted(rows, key=lambda r: (r[0], r[1])))
    Path(path).write_bytes(out)
    return Path(path)


# -- ArduPilot DataFlash ---------------------------------------------------------------
_FMT = ("BBnNZ", "Type,Length,Name,Format,Columns")
_STRUCT = {"B": "B", "Q": "Q", "f": "f", "I": "I", "H": "H", "n": "4s", "N": "16s", "Z": "64s"}
_IMU_NEW = ("QBffffffIIfBBHH", "TimeUS,I,GyrX,GyrY,GyrZ,AccX,AccY,AccZ,EG,EA,T,GH,AH,GHz,AHz")
_IMU_OLD = ("QffffffIIf", "TimeUS,GyrX,GyrY,GyrZ,AccX,AccY,AccZ,EG,EA,T")


def _df(mtype: int, fmt: str, *values) -> bytes:
    return bytes([0xA3, 0x95, mtype]) + struct.pack("<" + "".join(_STRUCT[c] for c in fmt),
                                                      *values)


def _df_fmt(mtype: int, name: str, fmt: str, cols: str) -> bytes:
    length = 3 + struct.calcsize("<" + "".join(_STRUCT[c] for c in fmt))
    return _df(0x80, _FMT[0], mtype, length, name.encode(), fmt.encode(), cols.encode())


def write_dataflash(path: Path, instances: dict[int, Series], old_style: bool = False,
                    params: dict[str, float] | None = None) -> Path:
    """New style: one ``IMU`` type with instance field ``I``; old style: ``IMU``, ``IMU2``,
    ``IMU3`` types without it. ``params``: PARM messages (Name, Value) at the start."""
    out = _df_fmt(0x80, "FMT", *_FMT)
    if params:
        out += _df_fmt(64, "PARM", "QNf", "TimeUS,Name,Value")
        out += b"".join(_df(64, "QNf", 0, k.encode(), float(v)) for k, v in params.items())
    names = {k: "IMU" if k == 0 else f"IMU{k + 1}" for k in instances}
    if old_style:
        for k in instances:
            out += _df_fmt(20 + k, names[k], *_IMU_OLD)
    else:
        out += _df_fmt(20, "IMU", *_IMU_NEW)
    rows = []
    for k, s in instances.items():
        for j in range(len(s.t_ns)):
            us, (x, y, z), temp = int(s.t_us[j]), s.gyro[j], float(s.temperature[j])
            if old_style:
                rows.append((j, k, _df(20 + k, _IMU_OLD[0], us, x, y, z, 0.0, 0.0, -9.81, 0, 0,
                                        temp)))
            else:
                rows.append((j, k, _df(20, _IMU_NEW[0], us, k, x, y, z, 0.0, 0.0, -9.81, 0, 0,
                                        temp, 1, 1, 1000, 1000)))
    out += b"".join(r[2] for r in sorted(rows, key=lambda r: (r[0], r[1])))
    Path(path).write_bytes(out)
    return Path(path)
