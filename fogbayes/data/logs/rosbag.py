"""ROS 1 bags, ROS 2 bags (folder, ``.db3``, ``.mcap``) and bare MCAP, read with rosbags.

``sensor_msgs/msg/Imu`` ``angular_velocity`` rad/s, time = ``header.stamp`` (sec + nanosec 1e-9);
``topic`` picks the Imu topic (several: an error listing them). One ``Temperature`` topic is
aligned (:mod:`.align`); several need ``topic="/imu,/temp"``. ``instance`` is an error.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ...errors import FogbayesError, TimeOrderError
from ._common import (LogSelectionError, NoGyroError, gyro_table, library_output, notes_meta,
                      require, sensor_id, unreadable)
from .align import interpolate_temperature

IMU = "sensor_msgs/msg/Imu"
TEMPERATURE = "sensor_msgs/msg/Temperature"


def kind_of(path: Path) -> str:
    """What the path holds, for messages."""
    if path.is_dir():
        return "ROS 2 bag"
    return {".bag": "ROS 1 bag", ".db3": "ROS 2 bag (sqlite3)"}.get(path.suffix.lower(),
                                                                   "MCAP file")


def read_rosbag(path: Path, *, topic: str | None, instance: int | None, axis: str):
    """The Table of one Imu topic of a bag (see the module doc)."""
    src = str(path)
    what = kind_of(path)
    if instance is not None:
        raise LogSelectionError(f"a {what} has no sensor instances", file=src,
                                column="--instance", fix="pick the IMU topic with --topic")
    imu_topic, temp_topic = _split(topic)
    highlevel = require("rosbags.highlevel")
    typesys = require("rosbags.typesys")
    # used only for bags that do not embed their message definitions (older .db3 files)
    store = typesys.get_typestore(typesys.Stores.ROS1_NOETIC if what == "ROS 1 bag"
                                  else typesys.Stores.ROS2_HUMBLE)
    with library_output() as notes:
        try:
            with highlevel.AnyReader([path], default_typestore=store) as reader:
                types = {c.topic: c.msgtype for c in reader.connections}
                imu_topic = _pick_imu(src, what, types, imu_topic)
                temp_topic = _pick_temperature(src, types, temp_topic)
                t, gyro, frame = _read_imu(reader, imu_topic)
                temp = _read_temperature(reader, temp_topic) if temp_topic else None
        except (FogbayesError, MemoryError):
            raise
        except Exception as exc:  # AnyReaderError, UnicodeDecodeError, ... on damaged files
            raise unreadable(src, what, exc) from None
    if t.size > 1 and np.all(t == t[0]):
        raise TimeOrderError(f"every message of {imu_topic} has the header stamp {t[0]!r} s "
                             "(the driver does not stamp its messages)", file=src,
                             column="time", row=1,
                             fix="record with a driver that fills header.stamp; the bag's "
                                 "receive times carry transport jitter and are not used")
    meta = {"log_format": what, "log_topic": imu_topic, "frame_id": frame,
            "time_source": f"{imu_topic} header.stamp", "sensor_id": sensor_id(path, imu_topic)}
    temperature = None
    if temp_topic is None:
        meta["temperature_alignment"] = f"none: the bag has no {TEMPERATURE} topic"
    else:
        temperature, aligned = interpolate_temperature(src, t, *temp, temp_topic)
        meta.update(aligned)
    meta.update(notes_meta(notes))
    return gyro_table(src, time=t, gyro=gyro, temperature=temperature, meta=meta, axis=axis,
                      what=f"topic {imu_topic}")


def _split(topic: str | None) -> tuple[str | None, str | None]:
    if topic is None:
        return None, None
    imu, _, temp = (p.strip() for p in str(topic).partition(","))
    return imu or None, temp or None


def _listing(types: dict) -> str:
    """The bag's topics and their types, for an error message."""
    rows = [f"{t} ({m})" for t, m in sorted(types.items())]
    if not rows:
        return "no topics"
    more = f", ... ({len(rows)} in all)" if len(rows) > 30 else ""
    return ", ".join(rows[:30]) + more


def _pick_imu(src: str, what: str, types: dict, topic: str | None) -> str:
    imus = sorted(t for t, m in types.items() if m == IMU)
    if topic is not None:
        if types.get(topic) == IMU:
            return topic
        where = f"is a {types[topic]} topic" if topic in types else "is not in the bag"
        raise LogSelectionError(f"'{topic}' {where}; the {IMU} topics: {imus or 'none'}",
                                file=src, column="--topic",
                                fix=f"use --topic {imus[0]}" if imus else
                                "record the IMU's sensor_msgs/Imu topic")
    if not imus:
        raise NoGyroError(f"the {what} has no {IMU} topic; it has {_listing(types)}", file=src,
                          fix="record the IMU's sensor_msgs/Imu topic")
    if len(imus) > 1:
        raise LogSelectionError(f"the {what} has {len(imus)} {IMU} topics: {imus}", file=src,
                                column="--topic", fix=f"pick one, e.g. --topic {imus[0]}")
    return imus[0]


def _pick_temperature(src: str, types: dict, topic: str | None) -> str | None:
    temps = sorted(t for t, m in types.items() if m == TEMPERATURE)
    if topic is not None:
        if types.get(topic) == TEMPERATURE:
            return topic
        raise LogSelectionError(f"'{topic}' is not a {TEMPERATURE} topic of the bag; those "
                                f"are {temps or 'none'}", file=src, column="--topic",
                                fix="give --topic IMU_TOPIC,TEMPERATURE_TOPIC with one of them"
                                if temps else "give --topic IMU_TOPIC alone")
    if len(temps) > 1:
        raise LogSelectionError(f"the bag has {len(temps)} {TEMPERATURE} topics: {temps}; "
                                "which one is the gyro's is not known", file=src,
                                column="--topic",
                                fix=f"name it after the IMU topic: --topic IMU_TOPIC,{temps[0]}")
    return temps[0] if temps else None


def _stamp(msg) -> tuple[int, int]:
    return msg.header.stamp.sec, msg.header.stamp.nanosec


def _messages(reader, topic: str):
    conns = [c for c in reader.connections if c.topic == topic]
    for conn, _, raw in reader.messages(connections=conns):
        yield reader.deserialize(raw, conn.msgtype)


def _read_imu(reader, topic: str):
    sec, nsec, gyro, frame = [], [], [], None
    for msg in _messages(reader, topic):
        s, n = _stamp(msg)
        sec.append(s)
        nsec.append(n)
        w = msg.angular_velocity
        gyro.append((w.x, w.y, w.z))
        frame = frame if frame is not None else msg.header.frame_id
    t = np.asarray(sec, dtype=np.float64) + np.asarray(nsec, dtype=np.float64) * 1e-9
    return t, np.asarray(gyro, dtype=np.float64).reshape(-1, 3), frame


def _read_temperature(reader, topic: str):
    sec, nsec, value = [], [], []
    for msg in _messages(reader, topic):
        s, n = _stamp(msg)
        sec.append(s)
        nsec.append(n)
        value.append(msg.temperature)
    t = np.asarray(sec, dtype=np.float64) + np.asarray(nsec, dtype=np.float64) * 1e-9
    return t, np.asarray(value, dtype=np.float64)
