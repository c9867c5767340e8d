"""Gyro logs read directly: PX4 ULog, ROS 1 and ROS 2 bags, MCAP, ArduPilot DataFlash (docs/logs.md).

:func:`read_log` returns a :class:`~fogbayes.data._read.Table` (``time`` s as logged,
``gyro_x/y/z`` and ``output`` rad/s, ``temperature`` deg C, metadata on format, topic, instance,
axis, time source, alignment) that :func:`fogbayes.data.load` checks. Libraries (extra ``logs``)
are imported inside the readers.
"""

from __future__ import annotations

import operator
from pathlib import Path

from ...errors import ArgumentError, FileFormatError, UnitError
from ..units import normalise_unit
from .._read import Table
from ._common import AXES, LOGS, LogSelectionError, NoGyroError, pick_axis

__all__ = ["AXES", "LOG_SUFFIXES", "LOGS", "LogSelectionError", "NoGyroError", "is_log",
           "read_log", "read_log_for_load"]

#: File suffixes read as logs (case-insensitive). A ROS 2 bag folder (holding
#: ``metadata.yaml``) is a log too, whatever its name.
LOG_SUFFIXES = (".ulg", ".bag", ".db3", ".mcap", ".bin")


def is_log(path: str | Path) -> bool:
    """Whether :func:`read_log` reads ``path`` (by suffix, or a ROS 2 bag folder)."""
    path = Path(path)
    if path.suffix.lower() in LOG_SUFFIXES:
        return True
    return path.is_dir() and (path / "metadata.yaml").is_file()


def read_log(path: str | Path, *, topic: str | None = None, instance: int | None = None,
             axis: str | None = None) -> Table:
    """Read one gyro of a log as a Table (see the module doc and docs/logs.md).

    Args:
        topic: PX4: ``sensor_gyro`` (default) or ``sensor_combined``; ROS: the
            ``sensor_msgs/Imu`` topic (default: the only one), optionally followed by
            ``,TEMPERATURE_TOPIC``; ArduPilot: the message type (``IMU``, ``IMU2``, ...).
        instance: PX4: the ``multi_id``; ArduPilot: the IMU number (default 0). ROS: none.
        axis: ``x`` (default), ``y`` or ``z``: the body axis copied into ``output``.

    Raises:
        FogbayesError: the library is missing (names the extra), the topic or instance
            is not in the log (lists what is), no gyro messages, a damaged file.
    """
    path = Path(path)
    src = str(path)
    a = pick_axis(axis)
    if instance is not None and not _sensor_number(instance):
        raise ArgumentError(f"instance {instance!r} is not a sensor number", column="--instance",
                            fix="give an integer >= 0 (0 is the first sensor)")
    if not path.exists():
        raise FileFormatError("file not found", file=src, fix="check the path")
    suffix = path.suffix.lower()
    if suffix == ".ulg" and path.is_file():
        from .ulog import read_ulog

        return read_ulog(path, topic=topic, instance=instance, axis=a)
    if suffix == ".bin" and path.is_file():
        from .dataflash import read_dataflash

        return read_dataflash(path, topic=topic, instance=instance, axis=a)
    if is_log(path):
        from .rosbag import read_rosbag

        return read_rosbag(path, topic=topic, instance=instance, axis=a)
    raise FileFormatError(f"not a gyro log ('{path.suffix}')", file=src,
                          fix=f"give a log ({', '.join(LOG_SUFFIXES)} or a ROS 2 bag folder)")


def read_log_for_load(path: Path, *, time: str, output: str, unit: str | None,
                      time_unit: str, topic, instance, axis) -> Table:
    """:func:`read_log` for :func:`fogbayes.data.load`, after refusing the options of
    :func:`~fogbayes.data.load` that would misread a log: its time is in seconds from its
    own stamps, its rates are in rad/s, its output is one of three axes (``output=
    "gyro_y"`` is another way to say ``axis="y"``)."""
    src = str(path)
    if time != "time" or time_unit not in (None, "s"):
        flag = "--time-column" if time != "time" else "--time-unit"
        raise ArgumentError(f"{flag} does not apply to a gyro log: its time stamps are read "
                            "in seconds from the log itself", file=src, column=flag,
                            fix=f"drop {flag}")
    if output != "output":
        picked = output[len("gyro_"):] if output in ("gyro_x", "gyro_y", "gyro_z") else None
        if picked is None or (axis is not None and str(axis).strip().lower() != picked):
            raise ArgumentError(f"--column {output} does not name an axis of a gyro log"
                                if picked is None else f"--column {output} and --axis {axis} "
                                "disagree", file=src, column="--column",
                                fix="pick the axis with --axis x, y or z (axis= in "
                                    "fogbayes.load)")
        axis = picked
    if unit and normalise_unit(unit, file=src) != "rad/s":
        raise UnitError(f"a gyro log holds rates in rad/s; reading them as {unit} would "
                        "scale them wrongly", file=src, column="--output-unit",
                        fix="drop --output-unit; to compensate a log, use a fit made on "
                            "rad/s data (e.g. on another log)")
    return read_log(path, topic=topic, instance=instance, axis=axis)


def _sensor_number(value) -> bool:
    try:
        return not isinstance(value, bool) and operator.index(value) >= 0
    except TypeError:
        return False
