"""PX4 ULog (``.ulg``), read with pyulog.

``sensor_gyro`` (``multi_id`` = ``instance``; ``x, y, z`` rad/s, ``temperature`` deg C), else
``sensor_combined`` (``gyro_rad``, no temperature). Time = ``timestamp_sample`` where present, else
``timestamp``, in us / 1e6. Dropouts and corruption are counted in the metadata, gaps never filled.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ._common import (LogSelectionError, NoGyroError, all_nan_temperature, gyro_table,
                      library_output, notes_meta, require, sensor_id, unreadable)

#: Gyro topics and their (x, y, z) fields, in the order tried when none is named.
TOPICS = {"sensor_gyro": ("x", "y", "z"),
          "sensor_combined": ("gyro_rad[0]", "gyro_rad[1]", "gyro_rad[2]")}


def read_ulog(path: Path, *, topic: str | None, instance: int | None, axis: str):
    """The Table of one gyro of a ULog file (see the module doc)."""
    src = str(path)
    if topic is not None and topic not in TOPICS:
        raise LogSelectionError(f"'{topic}' is not a gyro topic of PX4 logs", file=src,
                                column="--topic",
                                fix=f"use --topic {' or '.join(TOPICS)} (or leave it out)")
    pyulog = require("pyulog")
    with library_output() as notes:
        try:
            # both gyro topics, even with one named: an error can then say what there is
            ulog = pyulog.ULog(src, message_name_filter_list=list(TOPICS))
        except MemoryError:
            raise
        except Exception as exc:  # ULogException, struct.error, ... on a damaged file
            raise unreadable(src, "PX4 ULog file", exc) from None
    found = {}
    for d in ulog.data_list:
        found.setdefault(d.name, {})[d.multi_id] = d
    name = topic or next((t for t in TOPICS if t in found), None)
    if name is None:
        raise NoGyroError("the log holds no gyro messages (no sensor_gyro or sensor_combined)",
                          file=src, fix="log the gyro: set SDLOG_PROFILE to include high rate "
                                        "or sensor comparison, or keep the default profile "
                                        "(sensor_combined)")
    if name not in found:
        have = sorted(t for t in TOPICS if t in found)
        raise LogSelectionError(f"the log has no '{name}' messages; its gyro topics: {have}",
                                file=src, column="--topic",
                                fix=f"use --topic {have[0]}" if have else "log the gyro")
    k = 0 if instance is None else int(instance)
    if k not in found[name]:
        raise LogSelectionError(f"'{name}' has no instance {k}; the log has instances "
                                f"{sorted(found[name])}", file=src, column="--instance",
                                fix=f"use --instance {min(found[name])}")
    data = found[name][k].data
    fields = TOPICS[name]
    time_field = "timestamp_sample" if "timestamp_sample" in data else "timestamp"
    meta = {"log_format": "PX4 ULog", "log_topic": name, "log_instance": k,
            "time_source": f"{name}.{time_field} (us since boot)",
            "sensor_id": sensor_id(path, f"{name}[{k}]")}
    temp = None
    if "temperature" in data:
        temp = all_nan_temperature(np.asarray(data["temperature"], dtype=np.float64), meta,
                                   f"{name}.temperature")
        meta.setdefault("temperature_alignment", f"same message ({name}.temperature)")
    else:
        meta["temperature_alignment"] = f"none: {name} carries no temperature"
    if ulog.dropouts:
        meta["logging_dropouts"] = len(ulog.dropouts)
        meta["logging_dropout_ms"] = int(sum(d.duration for d in ulog.dropouts))
    if ulog.file_corruption:
        meta["file_corruption_detected"] = True
    # a thermal calibration fitted on rates PX4 already corrected is a fit of the leftover
    params = getattr(ulog, "initial_parameters", {}) or {}
    if "TC_G_ENABLE" in params:
        meta["px4_tc_g_enable"] = int(params["TC_G_ENABLE"])
    meta.update(notes_meta(notes))
    gyro = np.column_stack([np.asarray(data[f], dtype=np.float64) for f in fields])
    return gyro_table(src, time=np.asarray(data[time_field], dtype=np.float64) / 1e6,
                      gyro=gyro, temperature=temp, meta=meta, axis=axis,
                      what=f"{name} instance {k}")
