"""Recipe: the PAN satellite ETU gyro (ST LSM6DSM) cold thermal-vacuum test as Recordings.

Data: ``shared/data/measured/pan_lsm6dsm_tvac_cold/TVCtest3_7_20.csv`` (SOURCE.md, MIT).
time ms / 1000; gyro rad/s x 0.5; T = int16(raw) / 256 + 25 deg C (scale inferred). The run
cools monotonically, so T, dT/dt and time are almost collinear: a fit is valid along this run only.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..data.recording import Metadata, Recording
from ..errors import FileFormatError, MissingColumnError

GYRO_FACTOR = 0.5  # the authors' correction for their driver (commit f5f9cf7)
_COLUMNS = {"x": "gyrox rad/s", "y": "gyroy rad/s", "z": "gyroz rad/s"}


def pan_temperature(raw: np.ndarray) -> np.ndarray:
    """LSM6DSM OUT_TEMP word (read as uint16) -> deg C: int16(raw) / 256 + 25."""
    word = np.asarray(raw, dtype=np.int64).astype(np.uint16).view(np.int16)
    return word.astype(float) / 256.0 + 25.0


def load_pan_tvac(path: str | Path, axis: str = "x") -> Recording:
    """One gyro axis (``"x"``, ``"y"`` or ``"z"``) of the PAN TVAC test as a Recording (rad/s)."""
    import pandas as pd

    path = Path(path)
    if axis not in _COLUMNS:
        raise MissingColumnError(f"no gyro axis '{axis}'", file=str(path), column="axis",
                                 fix="use axis='x', 'y' or 'z'")
    if not path.is_file():
        raise FileFormatError("file not found", file=str(path),
                              fix="point to shared/data/measured/pan_lsm6dsm_tvac_cold/TVCtest3_7_20.csv")
    df = pd.read_csv(path)
    df.columns = [str(c).strip() for c in df.columns]
    for col in ("time (ms)", _COLUMNS[axis], "temp"):
        if col not in df.columns:
            raise MissingColumnError(f"no column '{col}' (have {list(df.columns)})",
                                     file=str(path), column=col,
                                     fix="use the TVCtest3_7_20.csv file described in SOURCE.md")
    meta = Metadata(sensor_id=f"PAN-ETU-LSM6DSM-{axis}", sample_rate=50.0, source=str(path),
                    extra={"recipe": "fogbayes.thermal.pan_tvac", "gyro_factor": GYRO_FACTOR,
                           "temperature": "int16(raw)/256 + 25 degC (inferred scale)"})
    return Recording(time=df["time (ms)"].to_numpy(float) / 1000.0,
                     output=GYRO_FACTOR * df[_COLUMNS[axis]].to_numpy(float), unit="rad/s",
                     temperatures=pan_temperature(df["temp"].to_numpy())[:, None],
                     temperature_names=("temperature",), meta=meta)


#: Fit options that suit the burst sampling: the temperature rate is taken from the
#: differences of consecutive bursts (300 s blocks, gaps bridged), the posterior on the
#: 1 s block means (no complete 10 s block exists inside a 5 s burst).
PAN_OPTIONS = {"rate_method": "difference", "rate_window_s": 300.0, "rate_gap_factor": 1e6,
               "bayes_average_s": 1.0}
