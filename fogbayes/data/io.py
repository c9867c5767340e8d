"""Load and save Recordings as CSV, Parquet or NPZ.

Column contract (DESIGN.md): ``time`` (s, strictly increasing), ``output`` (gyro output in
``unit``), ``temperature``, ``temperature_2``, ... (deg C), optional ``input_rate`` (deg/s).
Other names are mapped with the keyword arguments of :func:`load`.

CSV files may start with ``# key: value`` lines carrying metadata (``unit``,
``sensor_id``, ``sample_rate``, ``scale_factor``); :func:`save` writes them, so a CSV
round trip keeps everything. Numbers are written with 17 significant digits (exact).
Parquet keeps the metadata in the schema, NPZ in a ``__meta__`` JSON string.
"""

from __future__ import annotations

import difflib
import json
import re
from pathlib import Path
from typing import Sequence

import numpy as np

from ..errors import EmptyRecordingError, FileFormatError, FogbayesError, MissingColumnError, NonNumericError
from .recording import Metadata, Recording

FORMATS = {".csv": "csv", ".txt": "csv", ".parquet": "parquet", ".pq": "parquet", ".npz": "npz"}
_TEMP_RE = re.compile(r"^temperature(_\d+)?$")
_META_KEYS = ("unit", "sensor_id", "sample_rate", "scale_factor")


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
) -> Recording:
    """Read a Recording from ``path`` (format from the extension).

    Args:
        time, output: column names of the time (s) and gyro output columns.
        temperature: a column name or list of names; default: every column named
            ``temperature`` or ``temperature_<k>``, in that order (none is fine).
        input_rate: column of the reference rate (deg/s); used only if present, unless
            a non-default name is given, which is then required.
        unit: output unit; overrides the file's metadata (default ``deg/h``).
        scale_factor: raw units per deg/s, for V/mV/Hz outputs.
        sensor_id: overrides the file's metadata.

    Raises:
        FogbayesError: a subclass naming the file, column and row, and how to fix it.
    """
    path = Path(path)
    src = str(path)
    kind = FORMATS.get(path.suffix.lower())
    if kind is None:
        raise FileFormatError(f"unknown file type '{path.suffix}'", file=src,
                              fix="use .csv, .parquet or .npz")
    if not path.is_file():
        raise FileFormatError("file not found", file=src, fix="check the path")
    reader = {"csv": _read_csv, "parquet": _read_parquet, "npz": _read_npz}[kind]
    columns, meta = reader(path)
    if not columns or all(len(v) == 0 for v in columns.values()):
        raise EmptyRecordingError("the file holds no data rows", file=src,
                                  fix="check the file was written completely")

    def need(name: str, role: str) -> np.ndarray:
        if name not in columns:
            close = difflib.get_close_matches(name, list(columns), n=1, cutoff=0.5)
            hint = f"did you mean '{close[0]}'? " if close else ""
            raise MissingColumnError(
                f"no column '{name}' ({role}); the file has {list(columns)}", file=src,
                column=name, fix=f"{hint}rename the column or pass its name (e.g. --{role}-column)")
        return _as_float(columns[name], src, name)

    t = need(time, "time")
    y = need(output, "output")
    if temperature is None:
        tnames = sorted((c for c in columns if _TEMP_RE.match(c)), key=_temp_order)
    else:
        tnames = [temperature] if isinstance(temperature, str) else list(temperature)
    temps = np.column_stack([need(c, "temperature") for c in tnames]) if tnames else None
    rate = None
    if input_rate and (input_rate in columns or input_rate != "input_rate"):
        rate = need(input_rate, "input-rate")
    sr = meta.get("sample_rate")
    md = Metadata(
        sensor_id=sensor_id or str(meta.get("sensor_id", path.stem)),
        sample_rate=float(sr) if sr not in (None, "", "None") else None,
        source=src,
        extra={k: v for k, v in meta.items() if k not in _META_KEYS},
    )
    sf = scale_factor if scale_factor is not None else meta.get("scale_factor")
    return Recording(
        time=t, output=y, unit=unit or str(meta.get("unit", "deg/h")),
        temperatures=temps, temperature_names=tuple(tnames), input_rate=rate,
        scale_factor=float(sf) if sf not in (None, "", "None") else None, meta=md,
    )


def save(rec: Recording, path: str | Path) -> Path:
    """Write ``rec`` to ``path`` (format from the extension); :func:`load` reads it back."""
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
            **{k: v for k, v in rec.meta.extra.items() if _jsonable(v)}}
    path.parent.mkdir(parents=True, exist_ok=True)
    {"csv": _write_csv, "parquet": _write_parquet, "npz": _write_npz}[kind](path, cols, meta)
    return path


def write_table(path: str | Path, columns: dict[str, np.ndarray]) -> Path:
    """Write plain columns (e.g. a compensated output) as CSV, exact to 17 digits."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    _write_csv(path, columns, {})
    return path


# -- CSV -------------------------------------------------------------------------------
def _read_csv(path: Path):
    import pandas as pd

    meta, n_comment = {}, 0
    try:
        with open(path, encoding="utf-8") as fh:
            for line in fh:
                if not line.startswith("#"):
                    break
                n_comment += 1
                key, sep, value = line[1:].partition(":")
                if sep:
                    meta[key.strip()] = value.strip()
        df = pd.read_csv(path, skiprows=n_comment, skipinitialspace=True,
                         encoding="utf-8", low_memory=False)
    except FogbayesError:
        raise
    except pd.errors.EmptyDataError:
        raise EmptyRecordingError("the file is empty", file=str(path),
                                  fix="write a header line and data rows") from None
    except (pd.errors.ParserError, UnicodeDecodeError, ValueError, OSError) as exc:
        msg = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise FileFormatError(f"cannot parse as CSV ({msg})", file=str(path),
                              fix="use comma-separated columns with one header line and the "
                                  "same number of fields on every row") from None
    df.columns = [str(c).strip() for c in df.columns]
    return {c: df[c].to_numpy() for c in df.columns}, meta


def _write_csv(path: Path, cols: dict, meta: dict) -> None:
    names = list(cols)
    data = np.column_stack([np.asarray(cols[c], dtype=float) for c in names])
    header = "".join(f"# {k}: {v}\n" for k, v in meta.items() if v is not None and k in _META_KEYS)
    with open(path, "w", encoding="utf-8", newline="\n") as fh:
        fh.write(header + ",".join(names) + "\n")
        np.savetxt(fh, data, delimiter=",", fmt="%.17g")


def write_csv_mixed(path: str | Path, cols: dict[str, np.ndarray]) -> Path:
    """CSV with float columns at 17 digits and boolean columns as true/false."""
    import pandas as pd

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    pd.DataFrame(cols).to_csv(path, index=False, float_format="%.17g")
    return path


# -- Parquet ---------------------------------------------------------------------------
def _read_parquet(path: Path):
    import pyarrow as pa
    import pyarrow.parquet as pq

    try:
        table = pq.read_table(path)
    except (pa.ArrowException, OSError) as exc:
        raise FileFormatError(f"cannot read as Parquet ({exc})", file=str(path),
                              fix="check the file is a complete Parquet file") from None
    raw = (table.schema.metadata or {}).get(b"fogbayes", b"{}")
    return {c: table.column(c).to_numpy(zero_copy_only=False) for c in table.column_names}, json.loads(raw)


def _write_parquet(path: Path, cols: dict, meta: dict) -> None:
    import pyarrow as pa
    import pyarrow.parquet as pq

    table = pa.table({k: np.asarray(v, dtype=float) for k, v in cols.items()})
    table = table.replace_schema_metadata({b"fogbayes": json.dumps(meta).encode()})
    pq.write_table(table, path)


# -- NPZ -------------------------------------------------------------------------------
def _read_npz(path: Path):
    try:
        with np.load(path, allow_pickle=False) as z:
            cols = {k: z[k] for k in z.files if k != "__meta__"}
            meta = json.loads(str(z["__meta__"])) if "__meta__" in z.files else {}
    except (OSError, ValueError) as exc:
        raise FileFormatError(f"cannot read as NPZ ({exc})", file=str(path),
                              fix="write it with numpy.savez, one 1-D array per column") from None
    for k, v in cols.items():
        if v.ndim != 1:
            raise FileFormatError(f"array '{k}' has shape {v.shape}, expected 1-D", file=str(path),
                                  column=k, fix="store one 1-D array per column")
    return cols, meta


def _write_npz(path: Path, cols: dict, meta: dict) -> None:
    np.savez(path, __meta__=np.array(json.dumps(meta)),
             **{k: np.asarray(v, dtype=float) for k, v in cols.items()})


# -- helpers ---------------------------------------------------------------------------
def _as_float(values: np.ndarray, src: str, name: str) -> np.ndarray:
    """Convert a column to float64, naming the first cell that is not a number."""
    if values.dtype.kind in "fiu":
        return values.astype(float)
    if values.dtype.kind == "b":
        return values.astype(float)
    out = np.empty(len(values), dtype=float)
    for i, v in enumerate(values):
        if v is None or (isinstance(v, float) and np.isnan(v)):
            out[i] = np.nan  # empty cell: reported as non-finite by the Recording
            continue
        try:
            out[i] = float(str(v).strip())
        except ValueError:
            raise NonNumericError(f"'{v}' is not a number", file=src, column=name, row=i,
                                  fix="write plain decimal numbers (no units or text in cells)") from None
    return out


def _temp_order(name: str) -> int:
    return 1 if name == "temperature" else int(name.rsplit("_", 1)[1])


def _jsonable(v) -> bool:
    try:
        json.dumps(v)
        return True
    except TypeError:
        return False
