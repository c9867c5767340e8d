"""What every log reader shares: errors, quieting the libraries, and :func:`gyro_table`.

:func:`gyro_table` checks time order and builds the Table: exact repeats are removed and
counted in the metadata, any other non-increasing stamp is an error naming the message.
"""

from __future__ import annotations

import contextlib
import io
from pathlib import Path
from typing import Iterator

import numpy as np

from ...errors import (ArgumentError, EmptyRecordingError, FileFormatError, MissingColumnError,
                       TimeOrderError)
from .._read import Table

#: The body axes a log holds; ``axis`` picks one as the Recording's output.
AXES = ("x", "y", "z")
#: (extra, what needs it) for :func:`fogbayes.support.extras.require`.
LOGS = ("logs", "Gyro logs (ULog, ROS bags, MCAP, DataFlash)")
#: At most this many lines of what a library printed are kept in the metadata.
_NOTES = 5


class NoGyroError(EmptyRecordingError):
    """The log holds no gyro messages (no topic or message type that carries body rates)."""


class LogSelectionError(MissingColumnError):
    """The topic or instance asked for is not in the log, or more than one fits."""


def require(module: str):
    """Import a log library, or raise the one-line error naming the ``logs`` extra."""
    from ...support.extras import require as _require

    return _require(module, *LOGS)


def unreadable(src: str, what: str, exc: BaseException) -> FileFormatError:
    """The one-line error for a log the library cannot parse (no traceback)."""
    text = str(exc).strip()
    line = text.splitlines()[0] if text else type(exc).__name__
    line = line if len(line) <= 200 else line[:197] + "..."
    return FileFormatError(f"cannot read as {what} ({line})", file=src,
                           fix=f"check that the file is a complete {what} (copy it from the "
                               "vehicle again; a log cut off while written is damaged)")


def pick_axis(axis: str | None) -> str:
    """``x``, ``y`` or ``z`` (default ``x``)."""
    if axis is None:
        return "x"
    a = str(axis).strip().lower()
    if a not in AXES:
        raise ArgumentError(f"unknown axis {axis!r}", column="--axis",
                            fix="use --axis x, y or z (axis= in fogbayes.load)")
    return a


@contextlib.contextmanager
def library_output() -> Iterator[list[str]]:
    """Capture what a library prints (pymavlink, pyulog print warnings to stdout/stderr):
    ``--json -`` keeps stdout clean, and the lines go into the metadata instead of being
    lost. Yields a list that holds the captured lines once the block ends."""
    buf = io.StringIO()
    lines: list[str] = []
    try:
        with contextlib.redirect_stdout(buf), contextlib.redirect_stderr(buf):
            yield lines
    finally:
        lines.extend(ln.strip() for ln in buf.getvalue().splitlines() if ln.strip())


def notes_meta(lines: list[str]) -> dict:
    """Metadata of what the library printed: the first lines and how many there were."""
    if not lines:
        return {}
    return {"reader_notes": lines[:_NOTES], "reader_note_count": len(lines)}


def gyro_table(src: str, *, time, gyro, temperature, meta: dict, axis: str,
               what: str) -> Table:
    """The Table of one gyro: ``time``, ``gyro_x/y/z``, ``output`` (= ``gyro_<axis>``) and,
    when given, ``temperature``; ``what`` names the source (topic, instance) in errors."""
    t = np.asarray(time, dtype=np.float64)
    g = np.asarray(gyro, dtype=np.float64).reshape(-1, 3)
    temp = None if temperature is None else np.asarray(temperature, dtype=np.float64)
    if t.size == 0:
        raise NoGyroError(f"{what} holds no messages", file=src,
                          fix="pick a topic or instance that was logged (see the log's "
                              "contents with its own tools, e.g. ulog_info, ros2 bag info, "
                              "mavlogdump.py)")
    dt = np.diff(t)
    same = np.all(g[1:] == g[:-1], axis=1)
    if temp is not None:
        same &= (temp[1:] == temp[:-1]) | (np.isnan(temp[1:]) & np.isnan(temp[:-1]))
    repeat = (dt == 0) & same  # a message logged twice: the same sample, not a new one
    bad = np.flatnonzero((dt < 0) | ((dt == 0) & ~same))
    if bad.size:
        r = int(bad[0]) + 1
        how = "repeats with other values" if dt[bad[0]] == 0 else "goes back"
        raise TimeOrderError(
            f"the time stamp of {what} {how} at message {r} ({t[r - 1]!r} s -> {t[r]!r} s; "
            f"{bad.size} such step(s) in all)", file=src, column="time", row=r,
            fix="the log holds two runs or a clock reset: cut it at that message with the "
                "log's own tools, or read another topic/instance")
    meta = dict(meta)
    if repeat.any():
        keep = np.concatenate(([True], ~repeat))
        t, g = t[keep], g[keep]
        temp = None if temp is None else temp[keep]
        meta["repeated_messages_removed"] = int(repeat.sum())
    cols = {"time": t, "gyro_x": g[:, 0], "gyro_y": g[:, 1], "gyro_z": g[:, 2]}
    cols["output"] = cols[f"gyro_{axis}"]
    if temp is not None:
        cols["temperature"] = temp
    meta.setdefault("unit", "rad/s")
    meta["axis"] = axis
    meta["samples"] = int(t.size)
    return Table(cols, meta)


def all_nan_temperature(temp: np.ndarray | None, meta: dict, where: str) -> np.ndarray | None:
    """A temperature field the driver never filled (all NaN) is left out, and said so;
    one partly NaN is kept (the Recording names its first NaN row)."""
    if temp is not None and temp.size and np.all(np.isnan(temp)):
        meta["temperature_alignment"] = f"none: {where} is NaN in every message"
        return None
    return temp


def sensor_id(path: Path, source: str) -> str:
    """The file stem and the topic/instance: one log can hold several gyros."""
    stem = path.name if path.is_dir() else path.stem
    return f"{stem}:{source}"
