"""ArduPilot DataFlash binary logs (``.bin``), read with pymavlink's ``DFReader`` (Python indexer).

``IMU``: ``TimeUS`` (us since boot; oldest ``TimeMS``), ``GyrX/Y/Z`` rad/s body frame, ``T`` deg C,
instance column ``I`` (older logs ``IMU2``, ``IMU3``). ``instance`` picks the IMU, ``topic`` the
message type (``GYR``: ``SampleUS``, no temperature). Parser notes go into the metadata.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ...errors import FileFormatError
from ._common import (LogSelectionError, NoGyroError, all_nan_temperature, gyro_table,
                      library_output, notes_meta, require, sensor_id, unreadable)

#: Message types of older logs, by instance.
OLD_NAMES = ("IMU", "IMU2", "IMU3")
_HEAD = b"\xa3\x95"


def read_dataflash(path: Path, *, topic: str | None, instance: int | None, axis: str):
    """The Table of one IMU of a DataFlash log (see the module doc)."""
    src = str(path)
    with open(path, "rb") as fh:
        head = fh.read(3)
    if not head:
        raise FileFormatError("the file is empty", file=src,
                              fix="copy the log from the vehicle again")
    if head[:2] != _HEAD:  # every DataFlash log starts with its FMT messages
        raise FileFormatError(f"not an ArduPilot DataFlash binary log (it starts with "
                              f"{head[:2].hex(' ')}, not a3 95)", file=src,
                              fix="give the .bin log from the flight controller (a .log "
                                  "file is the text form: convert it with mavlogdump.py)")
    dfreader = require("pymavlink.DFReader")

    class _Reader(dfreader.DFReader_binary):
        def init_arrays_fast(self, progress_callback=None):
            self.init_arrays(progress_callback)  # Python indexer: its notes are captured

    with library_output() as notes:
        try:
            reader = _Reader(src, zero_time_base=False)
            try:
                name, k, key = _select(reader, src, topic, instance)
                rows = _rows(reader, src, name, k, key)
                params = _params(reader, ("AHRS_ORIENTATION", f"INS_TCAL{k + 1}_ENABLE"))
            finally:
                getattr(reader, "close", lambda: None)()  # pymavlink < 2.4.40 has none
        except (FileFormatError, LogSelectionError, NoGyroError, MemoryError):
            raise
        except Exception as exc:  # struct.error, ValueError, IndexError on damaged files
            raise unreadable(src, "ArduPilot DataFlash log", exc) from None
    if not rows["t"]:
        raise NoGyroError(f"the log has no {name} messages of instance {k}", file=src,
                          fix="check that the log holds IMU data (LOG_BITMASK)")
    meta = {"log_format": "ArduPilot DataFlash", "log_topic": name, "log_instance": k,
            "time_source": f"{name}.{rows['time_field']}",
            "sensor_id": sensor_id(path, f"{name}[{k}]")}
    temp = None
    if rows["temp_field"]:
        temp = all_nan_temperature(np.asarray(rows["temp"], dtype=np.float64), meta,
                                   f"{name}.{rows['temp_field']}")
        meta.setdefault("temperature_alignment", f"same message ({name}.{rows['temp_field']})")
    else:
        meta["temperature_alignment"] = f"none: {name} carries no temperature"
    # what the logged rates already went through (the firmware's thermal correction and
    # board rotation come before IMU logging): a thermal export needs neither
    if "AHRS_ORIENTATION" in params:
        meta["ardupilot_ahrs_orientation"] = int(params["AHRS_ORIENTATION"])
    if f"INS_TCAL{k + 1}_ENABLE" in params:
        meta["ardupilot_tcal_enable"] = int(params[f"INS_TCAL{k + 1}_ENABLE"])
    meta.update(notes_meta(notes))
    scale = 1e3 if rows["time_field"] == "TimeMS" else 1e6
    return gyro_table(src, time=np.asarray(rows["t"], dtype=np.float64) / scale,
                      gyro=np.asarray(rows["gyro"], dtype=np.float64), temperature=temp,
                      meta=meta, axis=axis, what=f"{name} instance {k}")


def _params(reader, names) -> dict:
    """The logged values (PARM messages) of ``names``, where the log has them."""
    if "PARM" not in reader.name_to_id:
        return {}
    reader.rewind()
    out = {}
    while (m := reader.recv_match(type="PARM")) is not None:
        if getattr(m, "Name", None) in names:
            out[m.Name] = m.Value
    return out


def _select(reader, src: str, topic: str | None, instance: int | None):
    """(message type, instance, instance column or None) asked for."""
    types = {n: reader.formats[i] for n, i in reader.name_to_id.items()}
    gyro = [n for n, f in types.items() if "GyrX" in f.columns and reader.counts[f.type] > 0]
    if not gyro:
        raise NoGyroError(f"the log holds no IMU messages; its types: {sorted(types)[:30]}",
                          file=src, fix="log the IMU (LOG_BITMASK bit IMU) and fly again")
    if topic is not None and topic not in gyro:
        raise LogSelectionError(f"the log has no gyro messages named '{topic}'; it has "
                                f"{sorted(gyro)}", file=src, column="--topic",
                                fix="leave --topic out and pick the IMU with --instance")
    if "I" in types.get(topic or "IMU", types[gyro[0]]).columns:  # ArduPilot >= 4.0
        # the instances present are known once the messages are read (_rows)
        return topic or ("IMU" if "IMU" in gyro else gyro[0]), instance or 0, "I"
    if topic is not None:
        k = OLD_NAMES.index(topic) if topic in OLD_NAMES else 0
        if instance is not None and int(instance) != k:
            raise LogSelectionError(f"--topic {topic} is instance {k}, not {instance}",
                                    file=src, column="--instance",
                                    fix="give --topic or --instance, not both")
        return topic, k, None
    k = 0 if instance is None else int(instance)
    have = [j for j, n in enumerate(OLD_NAMES) if n in gyro]
    if k not in have:
        raise LogSelectionError(f"the log has no IMU instance {k}; it has {have} "
                                f"({', '.join(OLD_NAMES[j] for j in have)})", file=src,
                                column="--instance", fix=f"use --instance {have[0]}")
    return OLD_NAMES[k], k, None


def _rows(reader, src: str, name: str, k: int, key: str | None) -> dict:
    """Time, rates and temperature of every ``name`` message of instance ``k``."""
    cols = reader.formats[reader.name_to_id[name]].columns
    # GYR (fast-sampled gyro) writes a batch under one TimeUS: its SampleUS is the sample's
    time_field = next(c for c in ("SampleUS", "TimeUS", "TimeMS") if c in cols or c == "TimeMS")
    temp_field = next((c for c in ("T", "Temp") if c in cols), None)
    t, gyro, temp, seen = [], [], [], set()
    while (m := reader.recv_match(type=name, strict=True)) is not None:
        if key is not None:
            j = int(getattr(m, key))
            seen.add(j)
            if j != k:
                continue
        t.append(getattr(m, time_field))
        gyro.append((m.GyrX, m.GyrY, m.GyrZ))
        if temp_field:
            temp.append(getattr(m, temp_field))
    if key is not None and k not in seen:
        have = sorted(seen)
        raise LogSelectionError(f"{name} has no instance {k}; the log has instances {have}",
                                file=src, column="--instance",
                                fix=f"use --instance {have[0]}" if have else "log the IMU")
    return {"t": t, "gyro": gyro, "temp": temp, "time_field": time_field,
            "temp_field": temp_field}
