"""Sequential column streams of .npy, .npz and Parquet files (for :mod:`fogbayes.stream.sources`, :mod:`.documents`).

``_scan_*`` read headers only and return ``(openers, lengths, metadata)``; ``_NpyStream.read(k)``
and ``_ParquetStream.read(k)`` return the next ``k`` rows as float64.
"""

from __future__ import annotations

import zipfile
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from ..errors import FileFormatError, MetadataError, NonNumericError

PARQUET_BATCH = 1 << 20  # rows per Parquet batch (one row group at most is decoded at once)


class _NpyStream:
    """A 1-D .npy array (or one field of a structured one) read sequentially from ``fh``."""

    def __init__(self, fh, src: str, name: str, field: str | None = None):
        self.fh, self.src, self.name, self.field = fh, src, name, field
        self.n, self.dtype = _npy_header(fh, src, name)

    def read(self, count: int) -> np.ndarray:
        raw = self.fh.read(count * self.dtype.itemsize)
        if len(raw) != count * self.dtype.itemsize:
            raise FileFormatError(f"the file ends early (wanted {count} more rows)", file=self.src,
                                  column=self.name, fix="check the file was written completely")
        a = np.frombuffer(raw, dtype=self.dtype)
        if self.field is not None:
            a = a[self.field]
        return _float(a, self.src, self.name)


def _npy_header(fh, src: str, name: str) -> tuple[int, np.dtype]:
    from ..data._read import read_npy_header

    try:
        shape, _, dtype = read_npy_header(fh)
    except (ValueError, OSError, EOFError) as exc:
        raise FileFormatError(f"cannot read a .npy header ({exc})", file=src, column=name,
                              fix="write the array with numpy.save / numpy.savez") from None
    if len(shape) != 1:
        raise FileFormatError(f"array '{name}' has shape {shape}, expected 1-D", file=src,
                              column=name, fix="store one 1-D array per column")
    if dtype.hasobject:
        raise NonNumericError(f"array '{name}' holds Python objects", file=src, column=name,
                              fix="store numbers (float64) without pickling")
    return int(shape[0]), dtype


def _float(a: np.ndarray, src: str, name: str) -> np.ndarray:
    if a.dtype.kind not in "fiub":
        raise NonNumericError(f"column '{name}' has type {a.dtype}, not a number", file=src,
                              column=name, fix="store the column as float64")
    return a.astype(np.float64)  # always a fresh, writeable, native-endian array


class _ParquetStream:
    """Parquet columns, re-cut from row-group batches into chunks of any size."""

    def __init__(self, path: Path, names: Sequence[str]):
        from ..support.extras import PARQUET, require

        pq = require("pyarrow.parquet", *PARQUET)

        self.names = list(names)
        self.src = str(path)
        self._it = pq.ParquetFile(path).iter_batches(batch_size=PARQUET_BATCH,
                                                     columns=self.names, use_threads=False)
        self._pending: list[dict[str, np.ndarray]] = []
        self._have = 0

    def read(self, count: int) -> dict[str, np.ndarray]:
        while self._have < count:
            batch = next(self._it, None)
            if batch is None:
                raise FileFormatError(f"the file ends early (wanted {count - self._have} more "
                                      "rows)", file=self.src, fix="check the file is complete")
            cols = {nm: _float(batch.column(i).to_numpy(zero_copy_only=False), self.src, nm)
                    for i, nm in enumerate(self.names)}
            self._pending.append(cols)
            self._have += batch.num_rows
        out = {nm: np.concatenate([p[nm] for p in self._pending]) for nm in self.names}
        rest = {nm: a[count:] for nm, a in out.items()}
        self._pending = [rest] if self._have > count else []
        self._have -= count
        return {nm: a[:count] for nm, a in out.items()}




def _npz_meta(fh, src: str) -> dict:
    """The JSON object in an NPZ's ``__meta__`` member; a pickled object is never loaded
    (``allow_pickle=False``): a :class:`~fogbayes.errors.MetadataError` naming ``src``."""
    from ._read import _json_meta

    fix = ("store the metadata as numpy.array(json.dumps(meta)), or write the file with "
           "fogbayes.save")
    try:
        arr = np.lib.format.read_array(fh, allow_pickle=False)
    except (ValueError, EOFError, OSError) as exc:  # an object array refused, or damaged
        raise MetadataError(f"the '__meta__' array cannot be read without unpickling "
                            f"({str(exc).splitlines()[0] if str(exc) else type(exc).__name__})",
                            file=src, fix=fix) from None
    if arr.dtype.kind not in "US" or arr.shape != ():
        raise MetadataError("the '__meta__' array is not a JSON string", file=src, fix=fix)
    return _json_meta(str(arr[()]), src, "the '__meta__' array")


def _scan_npz(path: Path):
    src = str(path)
    try:
        zf = zipfile.ZipFile(path)
    except (zipfile.BadZipFile, OSError) as exc:
        raise FileFormatError(f"cannot read as NPZ ({exc})", file=src,
                              fix="write it with numpy.savez, one 1-D array per column") from None
    with zf:
        infos = {i.filename[:-4]: i for i in zf.infolist() if i.filename.endswith(".npy")}
        meta = {}
        if "__meta__" in infos:
            with zf.open(infos.pop("__meta__")) as fh:
                meta = _npz_meta(fh, src)
        lengths = {}
        for nm, info in infos.items():
            with zf.open(info) as fh:
                lengths[nm] = _npy_header(fh, src, nm)[0]

    def opener(info):
        def open_member():  # a ZipFile per column: independent sequential streams
            z = zipfile.ZipFile(path)
            return _Closing(z.open(info), z), None
        return open_member

    return {nm: opener(i) for nm, i in infos.items()}, lengths, meta


class _Closing:
    """A zip member stream that also closes its ZipFile."""

    def __init__(self, fh, zf):
        self._fh, self._zf = fh, zf

    def read(self, k):
        return self._fh.read(k)

    def close(self):
        self._fh.close()
        self._zf.close()


def _scan_npy(path: Path):
    src = str(path)
    with open(path, "rb") as fh:
        n, dtype = _npy_header(fh, src, path.stem)
    if dtype.names:
        names = list(dtype.names)
    else:
        names = ["output"]

    def opener(field):
        def open_field():  # at the start: _NpyStream reads the header
            return open(path, "rb"), field
        return open_field

    cols = {nm: opener(nm if dtype.names else None) for nm in names}
    return cols, {nm: n for nm in names}, {}


def _scan_npy_dir(path: Path):
    files = sorted(path.glob("*.npy"))
    if not files:
        raise FileFormatError("the directory holds no .npy files", file=str(path),
                              fix="store one <column>.npy per column (e.g. time.npy, output.npy)")
    meta = {}
    if (path / "meta.json").is_file():
        from ._read import _json_meta

        meta = _json_meta((path / "meta.json").read_bytes(), str(path / "meta.json"),
                          "meta.json")
    lengths, cols = {}, {}
    for f in files:
        with open(f, "rb") as fh:
            lengths[f.stem] = _npy_header(fh, str(f), f.stem)[0]

        def open_file(f=f):
            return open(f, "rb"), None
        cols[f.stem] = open_file
    return cols, lengths, meta


def _scan_parquet(path: Path):
    from ..support.extras import PARQUET, require

    pa = require("pyarrow", *PARQUET)
    pq = require("pyarrow.parquet", *PARQUET)

    try:
        pf = pq.ParquetFile(path)
    except (pa.ArrowException, OSError) as exc:
        raise FileFormatError(f"cannot read as Parquet ({exc})", file=str(path),
                              fix="check the file is a complete Parquet file") from None
    schema = pf.schema_arrow
    from ._read import _json_meta

    meta = _json_meta((schema.metadata or {}).get(b"fogbayes", b"{}"), str(path),
                      "the schema metadata 'fogbayes'")
    n = pf.metadata.num_rows
    for field in schema:
        t = field.type
        if not (pa.types.is_floating(t) or pa.types.is_integer(t) or pa.types.is_boolean(t)):
            meta.setdefault("_non_numeric", []).append(field.name)
    return {nm: None for nm in schema.names}, {nm: n for nm in schema.names}, meta
