"""Write a large result column by column, chunk by chunk, without holding it in memory.

:func:`open_sink`: a folder of ``<column>.npy`` (final header first, plain appends), ``.npz``
(those files stored uncompressed, ZIP64) or ``.parquet`` (one row group per chunk). Atomic
(:mod:`fogbayes.data.atomic`): written under a hidden temporary name, renamed by
:meth:`Sink.close`, removed by :meth:`Sink.abort`; an existing folder target is replaced only if
it holds nothing but ``.npy`` files (:func:`check_sink`).
"""

from __future__ import annotations

import os
import shutil
import zipfile
from pathlib import Path

import numpy as np

from ..data.atomic import _fsync, _fsync_dir, _remove, atomic_dir, check_replaceable_dir, new_temp
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
        self._done = False
        self._w = {}
        if kind == "dir":  # a temporary folder beside the target, renamed in by close()
            self._atomic = atomic_dir(self.path)
            self._dir = self._atomic.__enter__()
        else:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            self._tmp = new_temp(self.path)
        try:
            if kind == "parquet":
                from ..support.extras import PARQUET, require

                pa = require("pyarrow", *PARQUET)
                pq = require("pyarrow.parquet", *PARQUET)

                schema = pa.schema([(nm, pa.from_numpy_dtype(np.dtype(dt)))
                                    for nm, dt in self.columns.items()])
                self._pq = pq.ParquetWriter(self._tmp, schema)
                self._schema = schema
            else:
                if kind == "npz":
                    self._dir = new_temp(Path(str(self.path) + ".parts"))
                    self._dir.mkdir()
                for nm, dt in self.columns.items():
                    self._w[nm] = NpyWriter(self._dir / f"{nm}.npy", n, dt)
        except BaseException:
            self.abort()
            raise

    def __enter__(self) -> Sink:
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        if exc_type is not None:
            self.abort()

    def write(self, **cols: np.ndarray) -> None:
        if self.kind == "parquet":
            from ..support.extras import PARQUET, require

            pa = require("pyarrow", *PARQUET)
            arrays = [pa.array(np.asarray(cols[nm], dtype=self.columns[nm]))
                      for nm in self.columns]
            self._pq.write_table(pa.Table.from_arrays(arrays, schema=self._schema))
        else:
            for nm, w in self._w.items():
                w.write(cols[nm])

    def close(self) -> Path:
        """Finish the output and rename it into place; on failure, :meth:`abort`."""
        try:
            if self.kind == "parquet":
                self._pq.close()
            else:
                for w in self._w.values():
                    w.close()
            if self.kind == "dir":
                self._done = True
                self._atomic.__exit__(None, None, None)  # fsync, rename into place
                return self.path
            if self.kind == "npz":
                with zipfile.ZipFile(self._tmp, "w", zipfile.ZIP_STORED,
                                     allowZip64=True) as zf:
                    for nm, w in self._w.items():
                        with open(w.path, "rb") as src, zf.open(f"{nm}.npy", "w",
                                                                force_zip64=True) as dst:
                            shutil.copyfileobj(src, dst, 1 << 22)
                        os.remove(w.path)
                self._dir.rmdir()
            _fsync(self._tmp)
            os.replace(self._tmp, self.path)
            self._done = True
        except BaseException:
            self.abort()
            raise
        _fsync_dir(self.path.parent)
        return self.path

    def abort(self) -> None:
        """Remove everything written so far; the target is left as it was."""
        if self._done:
            return
        self._done = True
        for w in self._w.values():
            try:
                w._fh.close()
            except Exception:  # noqa: BLE001  (cleanup goes on)
                pass
        if self.kind == "parquet" and hasattr(self, "_pq"):
            try:
                self._pq.close()
            except Exception:  # noqa: BLE001
                pass
        if self.kind == "dir":
            self._atomic.__exit__(FileFormatError, FileFormatError("aborted"), None)
            return
        if self.kind == "npz" and hasattr(self, "_dir"):
            _remove(self._dir)
        _remove(self._tmp)


def _kind(path) -> str:
    p = str(path)
    suffix = Path(p).suffix.lower()
    if p.endswith(("/", os.sep)) or suffix == "":
        return "dir"
    if suffix in (".parquet", ".pq"):
        return "parquet"
    if suffix == ".npz":
        return "npz"
    raise FileFormatError(f"cannot stream into a '{suffix}' file", file=p,
                          fix="write a directory of .npy files, .npz or .parquet")


def check_sink(path) -> None:
    """Refuse, before any work, an output :func:`open_sink` could not write or replace."""
    if _kind(path) == "dir":
        check_replaceable_dir(path)
    elif Path(path).is_dir():
        raise FileFormatError("is a folder, not a file", file=str(path),
                              fix="name a file, or remove the folder")


def open_sink(path, n: int, columns: dict) -> Sink:
    """A :class:`Sink` for ``columns`` (name -> dtype) of ``n`` rows at ``path``.

    Use it as ``with open_sink(...) as sink: ...; sink.close()`` so that an exception
    removes the partial output.
    """
    check_sink(path)
    return Sink(path, n, columns, _kind(path))
