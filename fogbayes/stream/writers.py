"""Write a large result column by column, chunk by chunk, without holding it in memory.

:func:`open_sink` picks the format from ``path``:

* a directory (a path without a suffix, or ending in ``/``): one ``<column>.npy`` per
  column. Each file gets its final header first (the row count is known) and the chunks
  are appended with plain writes, so the result is an ordinary .npy that
  ``np.load(mmap_mode="r")`` maps. Plain writes and not a writable memory map: the dirty
  pages of a map stay in the process's resident set, plain writes go through the page cache.
* ``.npz``: the same .npy files are written next to the target first and then stored (not
  compressed, ZIP64) into the archive one after the other, then removed. Readable by
  ``numpy.load`` and :func:`fogbayes.data.load` (and streamable by :mod:`.sources`).
* ``.parquet``: one row group per chunk through ``pyarrow.parquet.ParquetWriter``.

Memory: one chunk of each column.
"""

from __future__ import annotations

import os
import shutil
import zipfile
from pathlib import Path

import numpy as np

from ..errors import FileFormatError


class NpyWriter:
    """A 1-D .npy file of ``n`` rows of ``dtype``, appended chunk by chunk."""

    def __init__(self, path: Path, n: int, dtype):
        self.path, self.n, self.dtype = Path(path), int(n), np.dtype(dtype)
        self._fh = open(self.path, "wb")  # noqa: SIM115 - closed by close()
        header = {"descr": np.lib.format.dtype_to_descr(self.dtype), "fortran_order": False,
                  "shape": (self.n,)}
        np.lib.format.write_array_header_2_0(self._fh, header)
        self.written = 0

    def write(self, a: np.ndarray) -> None:
        a = np.ascontiguousarray(a, dtype=self.dtype)
        if self.written + a.size > self.n:
            raise FileFormatError(f"more rows than the {self.n} announced", file=str(self.path))
        self._fh.write(a.tobytes() if a.size < (1 << 16) else memoryview(a).cast("B"))
        self.written += a.size

    def close(self) -> None:
        self._fh.close()
        if self.written != self.n:
            raise FileFormatError(f"wrote {self.written} of {self.n} rows", file=str(self.path),
                                  fix="the stream ended early; rerun")


class Sink:
    """Columns written together, one chunk at a time; :meth:`close` finishes the file."""

    def __init__(self, path, n: int, columns: dict, kind: str):
        self.path, self.n, self.columns, self.kind = Path(path), int(n), dict(columns), kind
        if kind == "parquet":
            import pyarrow as pa
            import pyarrow.parquet as pq

            self.path.parent.mkdir(parents=True, exist_ok=True)
            schema = pa.schema([(nm, pa.from_numpy_dtype(np.dtype(dt)))
                                for nm, dt in self.columns.items()])
            self._pq = pq.ParquetWriter(self.path, schema)
            self._schema = schema
        else:
            self._dir = self.path if kind == "dir" else Path(str(self.path) + ".parts")
            self._dir.mkdir(parents=True, exist_ok=True)
            self._w = {nm: NpyWriter(self._dir / f"{nm}.npy", n, dt)
                       for nm, dt in self.columns.items()}

    def write(self, **cols: np.ndarray) -> None:
        if self.kind == "parquet":
            import pyarrow as pa

            arrays = [pa.array(np.asarray(cols[nm], dtype=self.columns[nm]))
                      for nm in self.columns]
            self._pq.write_table(pa.Table.from_arrays(arrays, schema=self._schema))
        else:
            for nm, w in self._w.items():
                w.write(cols[nm])

    def close(self) -> Path:
        if self.kind == "parquet":
            self._pq.close()
            return self.path
        for w in self._w.values():
            w.close()
        if self.kind == "npz":
            with zipfile.ZipFile(self.path, "w", zipfile.ZIP_STORED, allowZip64=True) as zf:
                for nm, w in self._w.items():
                    with open(w.path, "rb") as src, zf.open(f"{nm}.npy", "w",
                                                            force_zip64=True) as dst:
                        shutil.copyfileobj(src, dst, 1 << 22)
                    os.remove(w.path)
            self._dir.rmdir()
        return self.path


def open_sink(path, n: int, columns: dict) -> Sink:
    """A :class:`Sink` for ``columns`` (name -> dtype) of ``n`` rows at ``path``."""
    p = str(path)
    suffix = Path(p).suffix.lower()
    if p.endswith(("/", os.sep)) or suffix == "":
        return Sink(path, n, columns, "dir")
    if suffix in (".parquet", ".pq"):
        return Sink(path, n, columns, "parquet")
    if suffix == ".npz":
        return Sink(path, n, columns, "npz")
    raise FileFormatError(f"cannot stream into a '{suffix}' file", file=p,
                          fix="write a directory of .npy files, .npz or .parquet")
