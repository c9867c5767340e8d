"""Chunk iterators over a recording too large to load: NPZ, .npy and Parquet.

:func:`open_source` reads the header and gives a :class:`RecordSource` whose
:meth:`~RecordSource.chunks` yield float64 :class:`Chunk` s validated as a
:class:`fogbayes.data.Recording` (errors name file, column and global row), with the units and
plausibility rules of :func:`fogbayes.data.load`. Formats (:mod:`fogbayes.data.io`): ``.npz``
members streamed; a folder of ``<column>.npy``, a structured or 1-D ``.npy`` read with plain
reads (not mmap, to bound RSS); ``.parquet`` row groups re-cut to the chunk size.
"""

from __future__ import annotations

import difflib
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import NamedTuple

import numpy as np

from ..errors import (
    EmptyRecordingError,
    FileFormatError,
    MissingColumnError,
    NonFiniteError,
    NonNumericError,
    ShapeError,
    TimeOrderError,
)
from ..data.checks import check_temperature, check_time_step, finite, time_divisor
from ..data.temperature_columns import META_KEY as TEMPERATURES_KEY
from ..data.temperature_columns import temperature_columns
from ..data.units import normalise_unit
from ..data.column_streams import (
    _NpyStream,
    _ParquetStream,
    _scan_npy,
    _scan_npy_dir,
    _scan_npz,
    _scan_parquet,
)

DEFAULT_ROWS = 1 << 20  # rows per chunk: 8 MB per float64 column


class Chunk(NamedTuple):
    """Rows ``start .. start + n - 1`` of a recording (float64; None when not requested)."""

    start: int
    time: np.ndarray | None
    output: np.ndarray | None
    temperatures: np.ndarray | None  # (n, k), columns in ``RecordSource.temperature_names``
    input_rate: np.ndarray | None

    @property
    def n(self) -> int:
        for a in (self.time, self.output, self.temperatures, self.input_rate):
            if a is not None:
                return int(a.shape[0])
        return 0




class RecordSource:
    """A recording on disk: its columns, length and metadata, read chunk by chunk.

    Attributes:
        path, kind (``npz``, ``npy-dir``, ``npy``, ``parquet``), n (rows), columns (all
        names in the file), meta (the file's metadata dict); the role names ``time_name``,
        ``output_name``, ``temperature_names`` and ``input_rate_name`` (None if absent);
        ``unit``, ``scale_factor``, ``sensor_id``, ``sample_rate`` (None = unknown);
        ``time_divisor`` (file time units per second), ``temperature_scale`` and
        ``temperature_offset`` (deg C = scale x value + offset).
    """

    def __init__(self, path: Path, kind: str, n: int, columns: dict, meta: dict, roles: dict):
        self.path, self.kind, self.n = path, kind, n
        self._columns = columns  # name -> how to open it (kind-specific)
        self.columns = tuple(columns)
        self.meta = meta
        self.time_name = roles["time"]
        self.output_name = roles["output"]
        self.temperature_names: tuple[str, ...] = tuple(roles["temperature"])
        self.input_rate_name = roles["input_rate"]
        self.unit = roles["unit"]
        self.scale_factor = roles["scale_factor"]
        self.sensor_id = roles["sensor_id"]
        sr = meta.get("sample_rate")
        self.sample_rate = float(sr) if sr not in (None, "", "None") else None
        self.time_divisor = roles.get("time_divisor", 1.0)
        self.temperature_scale = roles.get("temperature_scale", 1.0)
        self.temperature_offset = roles.get("temperature_offset", 0.0)

    @property
    def source(self) -> str:
        return str(self.path)

    def require(self, *roles: str) -> None:
        """Raise :class:`MissingColumnError` unless the named roles have columns."""
        for role in roles:
            name = {"time": self.time_name, "output": self.output_name,
                    "input_rate": self.input_rate_name}.get(role, "x")
            if role == "temperature" and not self.temperature_names:
                raise MissingColumnError(f"no temperature column; the file has {list(self.columns)}",
                                         file=self.source, column="temperature",
                                         fix="add a 'temperature' column in deg C or name it")
            if role != "temperature" and (name is None or name not in self._columns):
                raise _missing(name or role, role, self.columns, self.source)

    def chunks(self, rows: int = DEFAULT_ROWS, *, fields: Sequence[str] = ("time", "output",
               "temperatures", "input_rate"), validate: bool = True,
               allow_nan: Sequence[str] = ()) -> Iterator[Chunk]:
        """Chunks of ``rows`` rows (the last one shorter), float64 and validated.

        ``fields``: which of time, output, temperatures, input_rate to read (the others are
        None, as is input_rate when the file has none). ``allow_nan``: fields in which NaN
        means a missing sample (e.g. ``("output",)`` for the Allan deviation).
        """
        rows = int(rows)
        if rows < 1:
            raise ShapeError(f"rows per chunk must be >= 1, got {rows}", column="rows",
                             fix="pass e.g. rows=1048576")
        want = {"time": [self.time_name] if "time" in fields else [],
                "output": [self.output_name] if "output" in fields else [],
                "temperatures": list(self.temperature_names) if "temperatures" in fields else [],
                "input_rate": ([self.input_rate_name] if "input_rate" in fields
                               and self.input_rate_name else [])}
        for role in ("time", "output"):
            if want[role]:
                self.require(role)
        names = list(dict.fromkeys(nm for v in want.values() for nm in v))
        reader, close = self._open(names)
        last_t = None
        try:
            for a in range(0, self.n, rows):
                cols = self._in_units(reader(min(rows, self.n - a)), want)
                if validate:
                    last_t = self._validate(cols, want, a, last_t, allow_nan)
                temps = want["temperatures"]
                yield Chunk(
                    a, cols[want["time"][0]] if want["time"] else None,
                    cols[want["output"][0]] if want["output"] else None,
                    np.column_stack([cols[t] for t in temps]) if temps else None,
                    cols[want["input_rate"][0]] if want["input_rate"] else None)
        finally:
            close()

    def _open(self, names):
        if self.kind == "parquet":
            ps = _ParquetStream(self.path, names)
            return ps.read, lambda: None
        streams, handles = {}, []
        for nm in names:
            fh, field = self._columns[nm]()
            handles.append(fh)
            streams[nm] = _NpyStream(fh, self.source, nm, field)
        return (lambda k: {nm: s.read(k) for nm, s in streams.items()},
                lambda: [h.close() for h in handles])

    def _in_units(self, cols: dict, want: dict) -> dict:
        """Times in seconds and temperatures in deg C (new arrays: readers reuse buffers)."""
        if self.time_divisor != 1.0 and want["time"]:
            nm = want["time"][0]
            cols[nm] = cols[nm] / self.time_divisor
        if (self.temperature_scale, self.temperature_offset) != (1.0, 0.0):
            for nm in want["temperatures"]:
                cols[nm] = self.temperature_scale * cols[nm] + self.temperature_offset
        return cols

    def _plausible(self, cols, want, start: int) -> None:
        """The in-memory loader's plausibility rules (:func:`fogbayes.data.checks.check_plausible`):
        every chunk's temperatures, the first chunk's sample rate."""
        for nm in want["temperatures"]:
            check_temperature(cols[nm], src=self.source, column=nm, first_row=start)
        if start == 0 and want["time"]:
            check_time_step(cols[want["time"][0]], src=self.source, column=want["time"][0])

    def _validate(self, cols, want, start, last_t, allow_nan):
        for role, names in want.items():
            for nm in names:
                a = cols[nm]
                bad = np.isinf(a) if role in allow_nan else ~np.isfinite(a)
                if bad.any():
                    i = int(np.flatnonzero(bad)[0])
                    raise NonFiniteError(f"value {a[i]} is NaN, empty or infinite", file=self.source,
                                         column=nm, row=start + i,
                                         fix="remove or repair those rows; fogbayes never fills "
                                             "gaps silently")
        if not want["time"]:
            self._plausible(cols, want, start)
            return last_t
        t = cols[want["time"][0]]
        dt = np.diff(t) if last_t is None else np.diff(t, prepend=last_t)
        bad = np.flatnonzero(dt <= 0)
        if bad.size:
            r = start + int(bad[0]) + (1 if last_t is None else 0)
            raise TimeOrderError(f"time does not increase at this row (step {dt[bad[0]]!r} s)",
                                 file=self.source, column=want["time"][0], row=r,
                                 fix="sort the rows by time and remove duplicate time stamps")
        self._plausible(cols, want, start)  # after the order check: the steps are > 0
        return float(t[-1]) if t.size else last_t


def _missing(name: str, role: str, have, src: str) -> MissingColumnError:
    close = difflib.get_close_matches(name, list(have), n=1, cutoff=0.5)
    hint = f"did you mean '{close[0]}'? " if close else ""
    return MissingColumnError(f"no column '{name}' ({role}); the file has {list(have)}", file=src,
                              column=name, fix=f"{hint}rename the column or pass its name")


# -- opening each format --------------------------------------------------------------------


def open_source(path, *, time: str = "time", output: str = "output",
                temperature: str | Sequence[str] | None = None,
                input_rate: str | None = "input_rate", unit: str | None = None,
                scale_factor: float | None = None, sensor_id: str | None = None,
                time_unit: str | None = None, temperature_scale: float = 1.0,
                temperature_offset: float = 0.0) -> RecordSource:
    """Open a large recording for chunked reading (arguments as :func:`fogbayes.data.load`).

    ``path``: ``.npz``, ``.parquet``/``.pq``, ``.npy`` or a directory of ``<column>.npy``.
    Only headers are read here.
    """
    path = Path(path)
    src = str(path)
    from ..data.time_units import unit_in_name

    divisor = time_divisor(time_unit or unit_in_name(time) or "s")  # None: as load reads it
    t_scale = finite(temperature_scale, "temperature_scale", nonzero=True)
    t_offset = finite(temperature_offset, "temperature_offset")
    if path.is_dir():
        kind, scan = "npy-dir", _scan_npy_dir
    else:
        suffix = path.suffix.lower()
        kinds = {".npz": ("npz", _scan_npz), ".npy": ("npy", _scan_npy),
                 ".parquet": ("parquet", _scan_parquet), ".pq": ("parquet", _scan_parquet)}
        if suffix not in kinds:
            raise FileFormatError(f"cannot stream a '{suffix}' file", file=src,
                                  fix="stream .npz, .npy (or a directory of them) or .parquet; "
                                      "convert CSV with fogbayes.data.load + save")
        if not path.is_file():
            raise FileFormatError("file not found", file=src, fix="check the path")
        kind, scan = kinds[suffix]
    cols, lengths, meta = scan(path)
    non_numeric = set(meta.pop("_non_numeric", []))
    if not cols:
        raise EmptyRecordingError("the file holds no columns", file=src,
                                  fix="check the file was written completely")
    if temperature is None:
        tnames = temperature_columns(cols, meta.get(TEMPERATURES_KEY), src)
    else:
        tnames = [temperature] if isinstance(temperature, str) else list(temperature)
    rate = input_rate if input_rate and (input_rate in cols or input_rate != "input_rate") else None
    used = [c for c in (time, output, rate, *tnames) if c]
    for c, role in [(rate, "input-rate")] + [(t, "temperature") for t in tnames]:
        if c and c not in cols:
            raise _missing(c, role, cols, src)
    for c in used:
        if c in non_numeric:
            raise NonNumericError(f"column '{c}' is not numeric", file=src, column=c,
                                  fix="store the column as float64")
    present = [c for c in used if c in lengths]
    n = lengths[present[0]] if present else next(iter(lengths.values()))
    for c in present:
        if lengths[c] != n:
            raise ShapeError(f"column '{c}' has {lengths[c]} rows but '{present[0]}' has {n}",
                             file=src, column=c, fix="give every column the same length")
    if n == 0:
        raise EmptyRecordingError("the file holds no data rows", file=src,
                                  fix="check the file was written completely")
    sf = scale_factor if scale_factor is not None else meta.get("scale_factor")
    roles = {"time": time, "output": output, "temperature": tnames, "input_rate": rate,
             "unit": normalise_unit(unit or str(meta.get("unit", "deg/h")), file=src),
             "scale_factor": float(sf) if sf not in (None, "", "None") else None,
             "sensor_id": sensor_id or str(meta.get("sensor_id", path.stem)),
             "time_divisor": divisor, "temperature_scale": t_scale,
             "temperature_offset": t_offset}
    return RecordSource(path, kind, n, cols, meta, roles)
