"""Put a separately published temperature (ROS ``sensor_msgs/Temperature``) on the gyro's stamps.

Linear interpolation between messages; outside their span the end values are held and
counted (``temperature_held_start``, ``temperature_held_end``).
"""

from __future__ import annotations

import numpy as np

from ...errors import TimeOrderError


def interpolate_temperature(src: str, t: np.ndarray, t_temp, values, topic: str):
    """(temperature on ``t``, metadata) from the messages (``t_temp``, ``values``) of
    ``topic``; (None, metadata) when the topic holds no messages."""
    ts = np.asarray(t_temp, dtype=np.float64)
    vs = np.asarray(values, dtype=np.float64)
    if ts.size == 0:
        return None, {"temperature_alignment": f"none: {topic} holds no messages"}
    dts = np.diff(ts)
    repeat = (dts == 0) & (vs[1:] == vs[:-1])
    bad = np.flatnonzero((dts < 0) | ((dts == 0) & ~repeat))
    if bad.size:
        r = int(bad[0]) + 1
        raise TimeOrderError(f"the stamps of {topic} do not increase at message {r} "
                             f"({ts[r - 1]!r} s -> {ts[r]!r} s)", file=src,
                             column="temperature", row=r,
                             fix="name another temperature topic with --topic IMU_TOPIC,"
                                 "TEMPERATURE_TOPIC, or cut the bag before that message")
    meta = {}
    if repeat.any():
        keep = np.concatenate(([True], ~repeat))
        ts, vs = ts[keep], vs[keep]
        meta["temperature_repeated_messages_removed"] = int(repeat.sum())
    before = int(np.count_nonzero(t < ts[0]))
    after = int(np.count_nonzero(t > ts[-1]))
    meta.update({
        "temperature_topic": topic,
        "temperature_messages": int(ts.size),
        "temperature_alignment": (
            f"linear interpolation of {topic} ({ts.size} messages) onto the gyro stamps; "
            f"{before} gyro samples before its first message and {after} after its last "
            "hold that message's value (no extrapolation)"),
        "temperature_held_start": before,
        "temperature_held_end": after,
    })
    return np.interp(t, ts, vs), meta  # np.interp holds the end values outside [ts0, ts-1]
