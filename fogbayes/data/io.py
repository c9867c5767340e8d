"""Load and save Recordings as CSV, Parquet or NPZ; load gyro logs (:mod:`fogbayes.data.logs`).

Columns (docs/DESIGN.md): ``time`` (s, increasing), ``output`` (``unit``), ``temperature``,
``temperature_2``, ... (deg C), ``input_rate`` (deg/s); other names mapped by :func:`load`'s
arguments. Metadata: CSV ``# key: value`` lines, Parquet schema, NPZ ``__meta__``; CSV numbers
with 17 significant digits. Logs by :func:`fogbayes.data.logs.read_log` (``topic``, ``instance``, ``axis``).
"""

from __future__ import annotations

import difflib
import json
from pathlib import Path
from typing import Sequence

import numpy as np

from ..errors import (ArgumentError, EmptyRecordingError, FileFormatError, FogbayesError,
                      MissingColumnError, NonNumericError)
from ._read import Table
from .checks import (check_plausible, finite, meta_float, meta_text, meta_unit, refuse_blank,
                     time_divisor)
from ._read import read_csv as _read_csv
from ._read import read_npz as _read_npz
from ._read import read_parquet as _read_parquet
from .atomic import atomic_path
from .logs import LOG_SUFFIXES, is_log, read_log_for_load  # libraries: only in the readers
from .recording import Metadata, Recording
from .temperature_columns import META_KEY as TEMPERATURES_KEY
from .temperature_columns import listed as listed_temperatures
from .temperature_columns import temperature_columns
from .time_units import named_time_columns, unit_in_name

#: ``meta.extra`` key saying how the time column was chosen (not written by :func:`save`:
#: a saved file's time is in seconds under ``time``).
TIME_READ_KEY = "time_read"

FORMATS = {".csv": "csv", ".txt": "csv", ".parquet": "parquet", ".pq": "parquet", ".npz": "npz"}
_META_KEYS = ("unit", "sensor_id", "sample_rate", "scale_factor", TEMPERATURES_KEY)


#: The command-line flag that names each column role (fogbayes/cli/_common.py).
_COLUMN_FLAGS = {"time": "--time-column", "output": "--column", "temperature": "--temperature",
                 "input-rate": "--input-rate-column"}


def load(
    path: str | Path,
    *,
    time: str = "time",
    output: str = "output",
    temperature: str | Sequence[str] | None = None,
    input_rate: str | None = "input_rate",
    unit: str | None = None,
    scale_factor: float | None = None,
    sensor_id: str | None = None,
    time_unit: str | None = None,
    temperature_scale: float = 1.0,
    temperature_offset: float = 0.0,
    topic: str | None = None,
    instance: int | None = None,
    axis: str | None = None,
    delimiter: str | None = None,
    decimal: str | None = None,
) -> Recording:
    """Read a Recording from ``path`` (format from the extension; a gyro log by its suffix
    ``.ulg``, ``.bag``, ``.db3``, ``.mcap``, ``.bin``, or a ROS 2 bag folder).

    Args:
        time, output: column names of the time and gyro output columns.
        temperature: a column name or list of names; default: every column named
            ``temperature`` or ``temperature_<k>``, in that order (none is fine).
        input_rate: column of the reference rate (deg/s); used only if present, unless
            a non-default name is given, which is then required.
        unit: output unit; overrides the file's metadata (default ``deg/h``).
        scale_factor: raw units per deg/s, for V/mV/Hz outputs.
        sensor_id: overrides the file's metadata.
        time_unit: unit of the time column: ``s``, ``ms``, ``us`` or ``ns`` (scaled to s).
            None: the unit the column's name states (``time_ms``, ``time [us]``,
            :mod:`fogbayes.data.time_units`), else ``s``. With the default ``time`` absent
            and one column whose name states a unit, that column is the time, read in
            that unit; either choice is recorded in ``meta.extra["time_read"]``.
        temperature_scale, temperature_offset: temperatures in deg C are
            ``temperature_scale * value + temperature_offset`` (raw sensor words, kelvin).
        topic, instance: gyro logs only: which gyro (:func:`fogbayes.data.logs.read_log`).
        axis: gyro logs only: ``x`` (default), ``y`` or ``z``, the body axis read as the
            output (``output="gyro_y"`` says the same).
        delimiter, decimal: CSV only: the field separator (``,``, ``;``, ``tab``) and the
            decimal mark (``.`` or ``,``); None sniffs them from the header and the
            first rows (:func:`fogbayes.data._read.sniff`), an error naming the option when
            two readings fit.

    The file is checked, not trusted (:mod:`fogbayes.data._read`): duplicate column
    names, ragged CSV rows, invalid metadata, damaged NPZ/Parquet files, a sample rate
    outside 1e-4 Hz ... 1 MHz and temperatures outside -100 ... 200 deg C are errors.
    Errors about a CSV row name its physical line (metadata, header and blank lines
    counted).

    Raises:
        FogbayesError: a subclass naming the file, column and row, and how to fix it.
    """
    path = Path(path)
    src = str(path)
    if time_unit is not None:
        time_divisor(time_unit)  # a bad unit fails before the file is read
    t_scale = finite(temperature_scale, "temperature_scale", nonzero=True)
    t_offset = finite(temperature_offset, "temperature_offset")
    if scale_factor is not None:
        scale_factor = finite(scale_factor, "scale_factor", positive=True)
    if is_log(path):
        for flag, value in (("--delimiter", delimiter), ("--decimal", decimal)):
            if value is not None:
                raise ArgumentError(f"{flag} applies to CSV files only, not to gyro logs",
                                    file=src, column=flag, fix=f"drop {flag}")
        table = read_log_for_load(path, time=time, output=output, unit=unit,
                                  time_unit=time_unit, topic=topic, instance=instance, axis=axis)
        time, output = "time", "output"
    else:
        for flag, value in (("--axis", axis), ("--topic", topic), ("--instance", instance)):
            if value is not None:
                raise ArgumentError(f"{flag} applies to gyro logs only, not to "
                                    f"'{path.suffix}' files", file=src, column=flag,
                                    fix=f"drop {flag}; name the column with --column "
                                        "(output= in fogbayes.load)")
        kind = FORMATS.get(path.suffix.lower())
        if path.is_dir():  # not a ROS 2 bag (is_log said so): say what it is, not its suffix
            raise FileFormatError("a folder, not a recording (and not a ROS 2 bag folder: no "
                                  "metadata.yaml)", file=src,
                                  fix="name one recording file in it (.csv, .parquet or .npz); "
                                      "'fogbayes pool' and 'fogbayes batch' take a folder")
        if kind is None:
            raise FileFormatError(f"unknown file type '{path.suffix}'", file=src,
                                  fix=f"use .csv, .parquet or .npz, or a gyro log "
                                      f"({', '.join(LOG_SUFFIXES)} or a ROS 2 bag folder)")
        if not path.is_file():
            raise FileFormatError("file not found", file=src, fix="check the path")
        if kind == "csv":
            table = _read_csv(path, delimiter=delimiter, decimal=decimal)
        else:
            for flag, value in (("--delimiter", delimiter), ("--decimal", decimal)):
                if value is not None:
                    raise ArgumentError(f"{flag} applies to CSV files only, not to "
                                        f"'{path.suffix}' files", file=src, column=flag,
                                        fix=f"drop {flag}")
            table = {"parquet": _read_parquet, "npz": _read_npz}[kind](path)
    time, time_unit, read_as = _time_column(table.columns, time, time_unit)
    divisor = time_divisor(time_unit)
    if read_as:
        table.meta[TIME_READ_KEY] = read_as
    try:
        return _recording(path, table, time=time, output=output, temperature=temperature,
                          input_rate=input_rate, unit=unit, scale_factor=scale_factor,
                          sensor_id=sensor_id, divisor=divisor, t_scale=t_scale,
                          t_offset=t_offset)
    except FogbayesError as exc:  # a data row of a CSV file: name its physical line
        lines = table.row_lines
        if exc.row is not None and lines is not None and exc.file == src \
                and 0 <= exc.row < len(lines):
            exc.located(line=int(lines[exc.row]))
        raise


def _time_column(columns, time: str, time_unit: str | None) -> tuple[str, str, str | None]:
    """(time column, its unit, how they were chosen or None): ``time_unit`` None takes the
    unit the name states; the default name ``time``, absent, is replaced by the one column
    whose name states a unit (:mod:`fogbayes.data.time_units`)."""
    picked = False
    if time == "time" and time not in columns:
        named = named_time_columns(columns)
        if len(named) == 1:
            time, picked = named[0], True
    if time_unit is not None:
        return time, time_unit, (f"'{time}' in {time_unit} (the only column whose name "
                                 "states a time unit)" if picked else None)
    named_unit = unit_in_name(time)
    if named_unit is None:
        return time, "s", None
    return time, named_unit, (f"'{time}' in {named_unit}, the unit its name states "
                              "(--time-unit overrides)")


def _recording(path: Path, table: Table, *, time, output, temperature, input_rate, unit,
               scale_factor, sensor_id, divisor, t_scale, t_offset) -> Recording:
    """The checked Recording from what a reader found in ``path``."""
    src = str(path)
    columns, meta = table.columns, table.meta
    if not columns or all(len(v) == 0 for v in columns.values()):
        raise EmptyRecordingError("the file holds no data rows", file=src,
                                  fix="check the file was written completely")
    for key in _META_KEYS:  # even where an argument overrides it: a value was forgotten
        refuse_blank(table, key, src)

    def need(name: str, role: str) -> np.ndarray:
        if name not in columns:
            close = difflib.get_close_matches(name, list(columns), n=1, cutoff=0.5)
            hint = f"did you mean '{close[0]}'? " if close else ""
            only = next(iter(columns)) if len(columns) == 1 else ""
            seps = [d for d in (";", "\t", ",", "|") if d in only]
            if seps:  # the header was not split: another separator than the one used
                shown = "tab" if seps[0] == "\t" else f"'{seps[0]}'"
                hint = (f"the header is one field holding {shown}: name the separator "
                        f"with --delimiter {shown} (delimiter= in fogbayes.load), or ")
            raise MissingColumnError(
                f"no column '{name}' ({role}); the file has {list(columns)}", file=src,
                column=name, fix=f"{hint}rename the column or pass its name "
                                 f"({_COLUMN_FLAGS[role]} NAME on the command line, {role.replace('-', '_')}= "
                                 "in fogbayes.load)")
        return _as_float(columns[name], src, name)

    t = need(time, "time")
    if divisor != 1.0:
        t = t / divisor
    y = need(output, "output")
    if temperature is None:
        tnames = temperature_columns(columns, meta.get(TEMPERATURES_KEY), src)
    else:
        tnames = [temperature] if isinstance(temperature, str) else list(temperature)
    temps = np.column_stack([need(c, "temperature") for c in tnames]) if tnames else None
    if temps is not None and (t_scale != 1.0 or t_offset != 0.0):
        temps = temps * t_scale + t_offset
    rate = None
    if input_rate and (input_rate in columns or input_rate != "input_rate"):
        rate = need(input_rate, "input-rate")
    md = Metadata(
        sensor_id=sensor_id or meta_text(table, "sensor_id", src) or path.stem,
        sample_rate=meta_float(table, "sample_rate", src, what="in Hz"),
        source=src,
        extra={k: v for k, v in meta.items() if k not in _META_KEYS},
    )
    sf = scale_factor if scale_factor is not None else \
        meta_float(table, "scale_factor", src, what="raw units per deg/s")
    rec = Recording(
        time=t, output=y, unit=unit or meta_unit(table, src),
        temperatures=temps, temperature_names=tuple(tnames), input_rate=rate,
        scale_factor=sf, meta=md,
    )
    check_plausible(rec, src=src, time_column=time, table=table)
    return rec


def save(rec: Recording, path: str | Path) -> Path:
    """Write ``rec`` to ``path`` (format from the extension); :func:`load` reads it back.

    Atomic (:mod:`fogbayes.data.atomic`): a temporary file beside ``path`` is renamed over
    it once complete, so ``path`` holds the old file or the new one, never a part.
    """
    path = Path(path)
    kind = FORMATS.get(path.suffix.lower())
    if kind is None:
        raise FileFormatError(f"unknown file type '{path.suffix}'", file=str(path),
                              fix="use .csv, .parquet or .npz")
    cols = {"time": rec.time, "output": rec.output}
    for j, name in enumerate(rec.temperature_names):
        cols[name] = rec.temperatures[:, j]
    if rec.input_rate is not None:
        cols["input_rate"] = rec.input_rate
    meta = {"unit": rec.unit, "sensor_id": rec.meta.sensor_id,
            "sample_rate": rec.meta.sample_rate, "scale_factor": rec.scale_factor,
            TEMPERATURES_KEY: listed_temperatures(rec.temperature_names),
            **{k: v for k, v in rec.meta.extra.items()
               if _jsonable(v) and k not in (TEMPERATURES_KEY, TIME_READ_KEY)}}
    with atomic_path(path) as tmp:
        {"csv": _write_csv, "parquet": _write_parquet, "npz": _write_npz}[kind](tmp, cols, meta)
    return path


def write_table(path: str | Path, columns: dict[str, np.ndarray]) -> Path:
    """Write plain columns (e.g. a compensated output) as CSV, exact to 17 digits (atomic)."""
    path = Path(path)
    with atomic_path(path) as tmp:
        _write_csv(tmp, columns, {})
    return path


# -- CSV (reading: fogbayes.data._read) -------------------------------------------------
def _write_csv(path: Path, cols: dict, meta: dict) -> None:
    names = list(cols)
    data = np.column_stack([np.asarray(cols[c], dtype=float) for c in names])
    header = "".join(f"# {k}: {v}\n" for k, v in meta.items() if v is not None and k in _META_KEYS)
    with open(path, "w", encoding="utf-8", newline="\n") as fh:
        fh.write(header + ",".join(names) + "\n")
        np.savetxt(fh, data, delimiter=",", fmt="%.17g")


def write_csv_mixed(path: str | Path, cols: dict[str, np.ndarray]) -> Path:
    """CSV with float columns at 17 digits and boolean columns as true/false (atomic)."""
    import pandas as pd

    path = Path(path)
    with atomic_path(path) as tmp:
        pd.DataFrame(cols).to_csv(tmp, index=False, float_format="%.17g")
    return path


# -- Parquet ---------------------------------------------------------------------------
def _write_parquet(path: Path, cols: dict, meta: dict) -> None:
    from ..support.extras import PARQUET, require

    pa = require("pyarrow", *PARQUET)
    pq = require("pyarrow.parquet", *PARQUET)

    table = pa.table({k: np.asarray(v, dtype=float) for k, v in cols.items()})
    table = table.replace_schema_metadata({b"fogbayes": json.dumps(meta).encode()})
    pq.write_table(table, path)


# -- NPZ -------------------------------------------------------------------------------
def _write_npz(path: Path, cols: dict, meta: dict) -> None:
    # a file object, not a name: numpy.savez would append ".npz" to a name like "x.NPZ"
    with open(path, "wb") as fh:
        np.savez(fh, __meta__=np.array(json.dumps(meta)),
                 **{k: np.asarray(v, dtype=float) for k, v in cols.items()})


# -- helpers ---------------------------------------------------------------------------
def _as_float(values: np.ndarray, src: str, name: str) -> np.ndarray:
    """Convert a column to float64, naming the first cell that is not a number."""
    if values.dtype.kind in "fiu":
        return values.astype(float)
    if values.dtype.kind == "b":  # true/false is a flag, never a measurement
        raise NonNumericError(f"'{values[0]}' is not a number (the column holds true/false)",
                              file=src, column=name, row=0,
                              fix="give numbers in this column, or name the right column")
    out = np.empty(len(values), dtype=float)
    for i, v in enumerate(values):
        if v is None or (isinstance(v, float) and np.isnan(v)):
            out[i] = np.nan  # empty cell: reported as non-finite by the Recording
            continue
        try:
            out[i] = float(str(v).strip())
        except ValueError:
            comma = "," in str(v) and _is_number(str(v).strip().replace(",", ".", 1))
            raise NonNumericError(f"'{v}' is not a number", file=src, column=name, row=i,
                                  fix="name the decimal mark with --decimal ',' (and the field "
                                      "separator with --delimiter)" if comma else
                                  "write plain decimal numbers (no units or text in cells)") from None
    return out



def _is_number(text: str) -> bool:
    try:
        float(text)
        return True
    except ValueError:
        return False


def _jsonable(v) -> bool:
    try:
        json.dumps(v)
        return True
    except TypeError:
        return False
