"""What a flight log says about its rates before any fit: already corrected, or rotated.

Logged gyro rates are after the firmware's thermal correction and board rotation (ArduPilot
``INS_TCAL<i>_ENABLE``, ``AHRS_ORIENTATION``; PX4 ``TC_G_ENABLE``); these parameters in the
metadata become warnings in the fit document and ``fogbayes export``.
"""

from __future__ import annotations

#: Prefix of these warnings in a fit document (``fogbayes export`` looks for it).
PREFIX = "firmware: "


def rate_warnings(extra: dict) -> list[str]:
    """Warnings for the metadata ``extra`` of a Recording read from a log (none for files)."""
    out = []
    inst = int(extra.get("log_instance", 0)) + 1
    if extra.get("ardupilot_tcal_enable") == 1:
        out.append(f"{PREFIX}the log was recorded with INS_TCAL{inst}_ENABLE = 1: its rates are "
                   "already temperature-corrected, so a thermal fit describes what the "
                   f"correction left; record with INS_TCAL{inst}_ENABLE = 0 to calibrate")
    if extra.get("ardupilot_ahrs_orientation") not in (None, 0):
        out.append(f"{PREFIX}the log was recorded with AHRS_ORIENTATION = "
                   f"{extra['ardupilot_ahrs_orientation']}: the logged x, y, z are rotated from "
                   "the sensor's, which INS_TCAL parameters act on")
    if extra.get("px4_tc_g_enable") == 1:
        out.append(f"{PREFIX}the log was recorded with TC_G_ENABLE = 1: its rates are already "
                   "temperature-corrected, so a thermal fit describes what the correction "
                   "left; record with TC_G_ENABLE = 0 to calibrate")
    return out
