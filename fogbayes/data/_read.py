"""The readers behind :func:`fogbayes.data.load`: never silently wrong data.

Each returns a :class:`Table` (columns, metadata, CSV line numbers) or raises a
:class:`~fogbayes.errors.FogbayesError` naming file, column, row or line and a fix. CSV:
``# key: value`` metadata; refused: duplicate columns, ragged rows, ``#`` after the header,
conflicting keys, NUL, non-UTF-8; separator and decimal mark sniffed (:func:`sniff`) or named
by ``--delimiter``/``--decimal``. NPZ: members checked against their bytes, numbers only, 1-D,
one length. Parquet: damaged files, duplicate names, non-object metadata. Plausibility:
:mod:`fogbayes.data.checks`.
"""

from __future__ import annotations

import csv
import io
import json
import math
import re
import sys
import zipfile
import zlib
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from ..errors import (ArgumentError, DuplicateColumnError, EmptyRecordingError, FileFormatError,
                      FogbayesError, MetadataError, RaggedRowError, ShapeError)



class Table(NamedTuple):
    """What a reader found in a file."""

    columns: dict[str, np.ndarray]
    meta: dict[str, Any]
    row_lines: np.ndarray | None = None  # CSV: 1-based physical line of each data row
    meta_lines: dict[str, int] = {}  # CSV: 1-based line of each metadata key


def _first_line(exc: BaseException) -> str:
    text = str(exc).strip()
    line = text.splitlines()[0] if text else type(exc).__name__
    return line if len(line) <= 200 else line[:197] + "..."


# -- CSV -------------------------------------------------------------------------------
#: Field separators tried when none is given, in this order, and their names for people.
SEPARATORS = {",": "','", ";": "';'", "\t": "tab"}
#: Decimal marks.
DECIMALS = (".", ",")
#: Data lines looked at to sniff the separator and the decimal mark.
SNIFF_LINES = 200
_COMMA_NUMBER = re.compile(r"[+-]?\d*,\d+(?:[eE][+-]?\d+)?")
_DOT_NUMBER = re.compile(r"[+-]?(?:\d+\.\d*|\.\d+)(?:[eE][+-]?\d+)?")


def _split(line: str, quoted: bool, sep: str = ",") -> list[str]:
    if not quoted:
        return line.split(sep)
    return next(csv.reader([line], delimiter=sep, skipinitialspace=True), [""])


def csv_option(value: str | None, flag: str) -> str | None:
    """A ``--delimiter`` (``,``, ``;``, ``tab`` or another single character) or ``--decimal``
    (``.`` or ``,``) value as one character; None stays None (sniff it)."""
    if value is None:
        return None
    v = {"tab": "\t", "\\t": "\t"}.get(str(value).strip().lower(), str(value))
    if flag == "--decimal":
        if v not in DECIMALS:
            raise ArgumentError(f"{flag} {value!r}: the decimal mark is '.' or ','",
                                column=flag, fix=f"give {flag} '.' or {flag} ','")
        return v
    if len(v) != 1 or v.isalnum() or v in "\"#.\n\r -+":
        raise ArgumentError(f"{flag} {value!r} cannot separate fields", column=flag,
                            fix=f"give one character, e.g. {flag} ',' or {flag} ';' or "
                                f"{flag} tab")
    return v


def _sample(body: bytes) -> list[str]:
    """The first :data:`SNIFF_LINES` non-blank, non-comment data lines of ``body``."""
    head = body[:1 << 16]
    lines = head.split(b"\n")
    if len(head) < len(body):
        lines = lines[:-1]  # the last one may be cut
    out = []
    for raw_line in lines:
        line = raw_line.decode("utf-8", errors="replace")
        if line.strip() and not line.lstrip().startswith("#"):
            out.append(line)
            if len(out) == SNIFF_LINES:
                break
    return out


def sniff(header: str, sample: list[str], quoted: bool, *, delimiter: str | None,
          decimal: str | None, src: str, line: int) -> tuple[str, str]:
    """The field separator and decimal mark of a CSV file: those given, else sniffed.

    Separator: each of :data:`SEPARATORS` that splits the header into two or more fields
    and every sampled data line into as many; one such is taken, none leaves the one that
    splits the header most (the ragged-row check then names the row), two or more are an
    error naming ``--delimiter``. Decimal mark: ``.`` with a ``,`` separator; otherwise ``,``
    when numbers in the sample are written ``0,63`` and none ``0.63``, ``.`` when the
    reverse or neither, an error naming ``--decimal`` when both.
    """
    if delimiter is None:
        fits = [d for d in SEPARATORS
                if len(h := _split(header, quoted, d)) > 1
                and all(len(_split(ln, quoted, d)) == len(h) for ln in sample)]
        if len(fits) > 1:
            names = " and ".join(SEPARATORS[d] for d in fits)
            raise FileFormatError(
                f"cannot tell the field separator: {names} each split the header and the "
                "first rows into the same number of fields", file=src, line=line,
                fix="name it, e.g. " + " or ".join(f"--delimiter {SEPARATORS[d]}"
                                                   for d in fits))
        delimiter = fits[0] if fits else max(
            SEPARATORS, key=lambda d: len(_split(header, quoted, d)))
    if decimal is None:
        decimal = "."
        if delimiter != ",":
            cells = [c.strip().strip('"') for ln in sample for c in _split(ln, quoted, delimiter)]
            comma = next((c for c in cells if _COMMA_NUMBER.fullmatch(c)), None)
            dot = next((c for c in cells if _DOT_NUMBER.fullmatch(c)), None)
            if comma is not None and dot is not None:
                raise FileFormatError(
                    f"cannot tell the decimal mark: the first rows hold both {comma!r} and "
                    f"{dot!r}", file=src, line=line,
                    fix="name it with --decimal ',' or --decimal '.' (and write every "
                        "number with that mark)")
            decimal = "," if comma is not None else "."
    if decimal == delimiter:
        raise ArgumentError(f"{SEPARATORS.get(delimiter, repr(delimiter))} cannot be both the "
                            "field separator and the decimal mark", file=src,
                            column="--decimal",
                            fix="name another separator, e.g. --delimiter ';' --decimal ','")
    return delimiter, decimal


def read_csv(path: Path, *, delimiter: str | None = None, decimal: str | None = None) -> Table:
    """Read a CSV recording; see the module doc for what is refused.

    ``delimiter`` (``,``, ``;``, ``tab``, ...) and ``decimal`` (``.`` or ``,``): None sniffs
    them (:func:`sniff`).
    """
    src = str(path)
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise FileFormatError(f"cannot read the file ({exc.strerror or _first_line(exc)})",
                              file=src, fix="check the path and its permissions") from None
    try:
        raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise FileFormatError(f"not UTF-8 text (byte 0x{raw[exc.start]:02x} at offset {exc.start})",
                              file=src, line=_line_of(raw, exc.start),
                              fix="save the file as UTF-8 CSV, or give a .parquet or .npz "
                                  "file") from None
    if raw.startswith(b"\xef\xbb\xbf"):  # a byte-order mark, as spreadsheet programs write
        raw = raw[3:]
    nul = raw.find(b"\x00")
    if nul >= 0:
        raise FileFormatError("the file holds NUL bytes: binary data, not CSV text", file=src,
                              line=_line_of(raw, nul),
                              fix="give a CSV text file (or name a binary file .npz/.parquet)")
    if b"\r" in raw:  # \r\n and a lone \r end a line, as in pandas' C parser
        raw = raw.replace(b"\r\n", b"\n").replace(b"\r", b"\n")

    # metadata and comment lines, then the header (a few lines: read one by one)
    meta: dict[str, str] = {}
    meta_lines: dict[str, int] = {}
    pos, n_line, header = 0, 0, None
    while pos < len(raw):
        end = raw.find(b"\n", pos)
        end = len(raw) if end < 0 else end
        line, pos, n_line = raw[pos:end].decode("utf-8"), end + 1, n_line + 1
        s = line.strip()
        if not s:
            continue
        if not s.startswith("#"):
            header = line
            break
        key, sep, value = s[1:].partition(":")
        key, value = key.strip(), value.strip()
        if sep and key:
            if key in meta and meta[key] != value:
                raise MetadataError(
                    f"'# {key}:' is given twice, as {meta[key]!r} on line {meta_lines[key]} "
                    f"and as {value!r}", file=src, line=n_line, fix=f"keep one '# {key}:' line")
            meta[key] = value
            meta_lines.setdefault(key, n_line)
    if header is None:
        raise EmptyRecordingError("the file is empty" if not meta else
                                  "the file holds '# key: value' lines but no header line",
                                  file=src, fix="write a header line and data rows")
    header_line = n_line
    body = raw[pos:]
    del raw
    quoted = b'"' in body or '"' in header
    sep, dec = sniff(header, _sample(body), quoted,
                     delimiter=csv_option(delimiter, "--delimiter"),
                     decimal=csv_option(decimal, "--decimal"), src=src, line=header_line)
    names = [c.strip() for c in _split(header, quoted, sep)]
    first: dict[str, int] = {}
    for k, name in enumerate(names):
        if not name:
            names[k] = name = f"Unnamed: {k}"  # as pandas names a column without a name
        if name in first:
            raise DuplicateColumnError(
                f"two columns are named '{name}' (fields {first[name] + 1} and {k + 1} of the "
                "header); pandas would silently rename the second one", file=src, column=name,
                line=header_line, fix="give every column its own name")
        first[name] = k

    # data lines: every non-blank line after the header, each with one field per column
    if quoted or b"#" in body:
        offsets, counts, body = _scan_lines(body, quoted, src, header_line, sep)
    else:
        offsets, counts, body = _scan_bytes(body, sep)
    if offsets.size == 0:
        raise EmptyRecordingError("the file has a header line but no data rows", file=src,
                                  fix="check the file was written completely")
    row_lines = header_line + 1 + offsets
    bad = np.flatnonzero(counts != len(names))
    if bad.size:
        r, n_bad = int(bad[0]), int(bad.size)
        more = f"; {n_bad - 1} more row(s) differ" if n_bad > 1 else ""
        how = "an extra" if counts[r] > len(names) else "a missing"
        other = next((d for d in SEPARATORS if d != sep and d in header), None)
        name = "--delimiter" if other is None else f"--delimiter {SEPARATORS[other]}"
        raise RaggedRowError(
            f"cannot parse as CSV: {counts[r]} field(s) where the header has {len(names)} "
            f"({how} field shifts the columns after it){more}", file=src, row=r,
            line=int(row_lines[r]),
            fix=f"give every row exactly one field per header column "
                f"({SEPARATORS.get(sep, repr(sep))} separates fields; write empty cells as "
                f"'{sep}{sep}'), or name the separator with {name} (and the decimal mark "
                "with --decimal)")
    columns = None
    if (dec == "." and not quoted and "pandas" not in sys.modules
            and offsets.size * len(names) <= NUMPY_FIELDS):
        columns = numeric_columns(body, len(names), sep)
    if columns is not None and len(columns[0]) == offsets.size:
        return Table(dict(zip(names, columns)), meta, row_lines, meta_lines)
    import pandas as pd

    try:
        df = pd.read_csv(io.BytesIO(body), header=None, names=names, index_col=False,
                         sep=sep, decimal=dec,
                         skipinitialspace=True, skip_blank_lines=False, low_memory=False,
                         encoding="utf-8")
    except (pd.errors.ParserError, ValueError, OverflowError) as exc:
        raise FileFormatError(f"cannot parse as CSV ({_first_line(exc)})", file=src,
                              fix="use comma-separated columns with one header line and the "
                                  "same number of fields on every row") from None
    if len(df) != offsets.size:  # quoting that spans lines: never guess which row is which
        raise FileFormatError(f"cannot parse as CSV: {offsets.size} data lines gave {len(df)} "
                              "rows", file=src,
                              fix="write one row per line, without quoted line breaks")
    return Table({c: df[c].to_numpy() for c in names}, meta, row_lines, meta_lines)


#: fields up to which a CSV body is parsed by NumPy where pandas is not loaded yet: importing
#: pandas costs ~0.25 s, NumPy's parser ~0.2 us a field more than pandas' C parser (the two
#: break even near 1e6 fields; a process that has pandas already keeps using it)
NUMPY_FIELDS = 1_000_000
#: bytes of a body NumPy reads as pandas does: digits, signs, '.', exponents, blanks, newlines
#: (NumPy also takes 'nAn' or '+nan' as NaN where pandas keeps text: such bodies go to pandas)
_NUMERIC_BYTES = np.zeros(256, dtype=bool)
_NUMERIC_BYTES[list(b"0123456789+-.eE \t\n")] = True


def numeric_columns(body: bytes, n_columns: int, sep: str) -> list[np.ndarray] | None:
    """The ``n_columns`` columns of an unquoted, '.'-decimal CSV body (no header, no blank
    lines) whose every field is a number, as pandas' C parser gives them: int64 where every
    field of the column is an integer, float64 otherwise; None where a field is anything else
    (empty, text, NaN or inf spelt out, an integer beyond int64), which pandas then reads.
    """
    if len(sep.encode()) != 1:  # a separator beyond ASCII ('§'): pandas splits it
        return None
    allowed = _NUMERIC_BYTES.copy()
    allowed[ord(sep)] = True
    if not allowed[np.frombuffer(body, dtype=np.uint8)].all():
        return None
    try:
        values = np.loadtxt(io.BytesIO(body), delimiter=sep, dtype=np.float64, comments=None,
                            ndmin=2)
    except ValueError:
        return None
    if values.shape[1] != n_columns:
        return None
    columns = []
    for k in range(n_columns):
        col = np.ascontiguousarray(values[:, k])
        if np.all(col == np.round(col)) and np.all(np.abs(col) < 2.0 ** 63):
            try:  # "5" in every row: int64 as pandas makes it; "5.0" somewhere: float64
                col = np.loadtxt(io.BytesIO(body), delimiter=sep, dtype=np.int64,
                                 comments=None, usecols=k, ndmin=1)
            except ValueError:
                pass
        elif np.all(col == np.round(col)):
            return None  # pandas reads integers beyond int64 as uint64 or text
        columns.append(col)
    return columns


def _line_of(raw: bytes, offset: int) -> int:
    """1-based physical line of byte ``offset`` (\\n, \\r\\n and a lone \\r end lines)."""
    head = raw[:offset]
    return head.count(b"\n") + head.count(b"\r") - head.count(b"\r\n") + 1


_BLANK = np.zeros(256, dtype=bool)
_BLANK[[9, 10, 11, 12, 32]] = True  # tab, newline, vertical tab, form feed, space


def _scan_bytes(body: bytes, sep: str = ",") -> tuple[np.ndarray, np.ndarray, bytes]:
    """Data lines of an unquoted CSV body without comment lines, vectorised: the 0-based
    offset of each non-blank line, its number of fields (``sep`` + 1), and the body without
    blank lines."""
    a = np.frombuffer(body, dtype=np.uint8)
    starts = np.flatnonzero(a == 10) + 1
    starts = np.concatenate(([0], starts[starts < a.size]))
    if a.size == 0:
        return np.zeros(0, np.int64), np.zeros(0, np.int64), body
    text = np.add.reduceat(~_BLANK[a], starts, dtype=np.int64) > 0
    commas = np.add.reduceat(a == ord(sep), starts, dtype=np.int64)
    offsets = np.flatnonzero(text)
    if offsets.size != starts.size:  # blank lines: drop them, so rows match data lines
        ends = np.concatenate((starts[1:], [a.size]))
        body = b"".join(body[starts[k]:ends[k]] for k in offsets)
        if body and not body.endswith(b"\n"):
            body += b"\n"
    return offsets, commas[offsets] + 1, body


def _scan_lines(body: bytes, quoted: bool, src: str, header_line: int, sep: str = ","):
    """:func:`_scan_bytes` line by line, for quoted fields and '#' characters."""
    offsets, counts, keep = [], [], []
    for k, raw_line in enumerate(body.split(b"\n")):
        line = raw_line.decode("utf-8")
        if not line or line.isspace():
            continue
        if line.lstrip()[:1] == "#":
            raise FileFormatError(
                "a '#' line after the header: metadata and comments belong before it",
                file=src, line=header_line + 1 + k,
                fix="move '# key: value' lines above the header line and delete comment "
                    "lines between data rows (two files joined into one?)")
        offsets.append(k)
        counts.append(len(_split(line, quoted, sep)) if quoted else line.count(sep) + 1)
        keep.append(raw_line)
    return (np.asarray(offsets, dtype=np.int64), np.asarray(counts, dtype=np.int64),
            b"\n".join(keep) + b"\n")


# -- Parquet ---------------------------------------------------------------------------
def read_parquet(path: Path) -> Table:
    """Read a Parquet recording; metadata from the schema key ``fogbayes`` (a JSON object)."""
    from ..support.extras import PARQUET, require

    pq = require("pyarrow.parquet", *PARQUET)

    src = str(path)
    fix = "check the file is a complete Parquet file (write it again)"
    try:
        # names first: pyarrow refuses duplicate names with a message that does not say so
        _no_duplicates([str(c) for c in pq.read_schema(path).names], src, "column")
        table = pq.read_table(path)
    except FogbayesError:
        raise
    except MemoryError:
        raise
    except Exception as exc:  # pyarrow raises ArrowInvalid, ArrowIOError, OSError, ...
        raise FileFormatError(f"cannot read as Parquet ({_first_line(exc)})", file=src,
                              fix=fix) from None
    names = [str(c) for c in table.column_names]
    _no_duplicates(names, src, "column")
    cols = {}
    for j, name in enumerate(names):
        try:
            cols[name] = table.column(j).to_numpy(zero_copy_only=False)
        except MemoryError:
            raise
        except Exception as exc:
            raise FileFormatError(f"cannot read column as an array ({_first_line(exc)})",
                                  file=src, column=name,
                                  fix="store every column as plain numbers") from None
    raw = (table.schema.metadata or {}).get(b"fogbayes")
    meta = {} if raw is None else _json_meta(raw, src, "the schema metadata 'fogbayes'")
    return Table(cols, meta)


def _json_meta(raw, src: str, where: str) -> dict:
    try:
        meta = json.loads(raw.decode("utf-8") if isinstance(raw, bytes) else raw)
    except (UnicodeDecodeError, json.JSONDecodeError, RecursionError) as exc:
        raise MetadataError(f"{where} is not JSON ({_first_line(exc)})", file=src,
                            fix="write the file with fogbayes.save (metadata as a JSON "
                                "object)") from None
    if not isinstance(meta, dict):
        raise MetadataError(f"{where} is a JSON {type(meta).__name__}, not an object",
                            file=src, fix="store the metadata as a JSON object "
                                          "{\"unit\": ..., \"sample_rate\": ...}")
    return meta


def _no_duplicates(names: list[str], src: str, what: str) -> None:
    seen: dict[str, int] = {}
    for k, name in enumerate(names):
        if name in seen:
            raise DuplicateColumnError(
                f"two {what}s are named '{name}' (positions {seen[name] + 1} and {k + 1})",
                file=src, column=name, fix="give every column its own name")
        seen[name] = k


# -- NPZ -------------------------------------------------------------------------------
_NPZ_FIX = "write it with numpy.savez (or fogbayes.save), one 1-D numeric array per column"


def read_npz(path: Path) -> Table:
    """Read an NPZ recording without trusting its headers (see the module doc)."""
    src = str(path)
    try:
        with zipfile.ZipFile(path) as zf:
            infos = zf.infolist()
            names = [info.filename for info in infos]
            bad = [n for n in names if not n.endswith(".npy")]
            if bad:
                raise FileFormatError(f"archive member '{bad[0]}' is not a .npy array",
                                      file=src, fix=_NPZ_FIX)
            keys = [n[:-4] for n in names]
            _no_duplicates(keys, src, "array")
            arrays = {key: _read_member(zf, info, key, src) for key, info in zip(keys, infos)}
    except FogbayesError:
        raise
    except MemoryError:
        raise
    except (zipfile.BadZipFile, zipfile.LargeZipFile, OSError, EOFError, ValueError,
            zlib.error, NotImplementedError, RuntimeError, KeyError, OverflowError) as exc:
        raise FileFormatError(f"cannot read as NPZ ({_first_line(exc)})", file=src,
                              fix=_NPZ_FIX) from None
    meta_arr = arrays.pop("__meta__", None)
    meta = {} if meta_arr is None else _json_meta(str(meta_arr[()]), src, "the '__meta__' array")
    if "columns" in arrays or ("data" in arrays and arrays["data"].ndim == 2):
        arrays = _matrix_layout(arrays, meta, src)
    length = None
    for key, arr in arrays.items():
        if arr.ndim != 1:
            raise FileFormatError(f"array '{key}' has shape {arr.shape}, expected 1-D", file=src,
                                  column=key, fix="store one 1-D array per column")
        if length is None:
            length = (key, arr.size)
        elif arr.size != length[1]:
            raise ShapeError(f"array '{key}' has {arr.size} rows but '{length[0]}' has "
                             f"{length[1]}", file=src, column=key,
                             fix="store columns of one length (one value per time stamp)")
    return Table(arrays, meta)


def _matrix_layout(arrays: dict, meta: dict, src: str) -> dict:
    """Columns from the matrix layout: a 2-D ``data`` array, its column names in ``columns``
    (strings) and, optionally, the sample rate in ``fs_hz`` (a scalar; a ``time`` column of
    ``k / fs_hz`` is made when the file has none). Data sets such as the ADIS16405 static
    runs (R package imudata) come this way."""
    fix = ("store a 2-D 'data' array (rows = samples), its column names as a 1-D string "
           "array 'columns' and the sample rate as 'fs_hz', or one 1-D array per column")
    data, names = arrays.pop("data", None), arrays.pop("columns", None)
    if data is None or data.ndim != 2 or names is None or names.ndim != 1 \
            or names.dtype.kind != "U" or names.size != data.shape[1]:
        got = "no 'data'" if data is None else f"'data' of shape {data.shape}"
        raise FileFormatError(f"matrix layout: {got} and "
                              f"{'no' if names is None else names.size} column name(s)",
                              file=src, column="columns" if names is not None else "data",
                              fix=fix)
    _no_duplicates([str(c) for c in names], src, "column")
    cols = {str(c): np.ascontiguousarray(data[:, j]) for j, c in enumerate(names)}
    clash = sorted(set(cols) & set(arrays))
    if clash:
        raise DuplicateColumnError(f"column '{clash[0]}' is both in 'data' and an array of "
                                   "its own", file=src, column=clash[0], fix=fix)
    fs = arrays.pop("fs_hz", None)
    if fs is not None:
        if fs.size != 1 or not np.isfinite(fs.ravel()[0]) or fs.ravel()[0] <= 0:
            raise MetadataError("'fs_hz' must be one positive sample rate", file=src,
                                column="fs_hz", fix=fix)
        meta.setdefault("sample_rate", float(fs.ravel()[0]))
        if "time" not in arrays and "time" not in cols:
            cols["time"] = np.arange(data.shape[0]) / float(fs.ravel()[0])
            meta.setdefault("time", "made from fs_hz (the file has no time stamps)")
    cols.update(arrays)
    return cols


def read_npy_header(fh) -> tuple[tuple[int, ...], bool, np.dtype]:
    """(shape, fortran order, dtype) of the .npy stream ``fh``, read without the data."""
    fmt = np.lib.format
    version = fmt.read_magic(fh)
    if version == (1, 0):
        return fmt.read_array_header_1_0(fh)
    if version == (2, 0):
        return fmt.read_array_header_2_0(fh)
    return fmt._read_array_header(fh, version)


def _read_member(zf: zipfile.ZipFile, info: zipfile.ZipInfo, key: str, src: str) -> np.ndarray:
    with zf.open(info) as fh:
        shape, fortran, dtype = read_npy_header(fh)
        if key == "__meta__":
            if dtype.kind not in "US" or shape != ():
                raise MetadataError("the '__meta__' array is not a JSON string", file=src,
                                    fix="store the metadata as numpy.array(json.dumps(meta))")
        elif dtype.hasobject:
            raise FileFormatError(f"array '{key}' holds Python objects (pickled data is never "
                                  "loaded)", file=src, column=key, fix=_NPZ_FIX)
        elif key == "columns" and dtype.kind == "U" and len(shape) == 1:
            pass  # the names of a 2-D 'data' array's columns (matrix layout, see read_npz)
        elif dtype.kind not in "biuf" or dtype.fields is not None:
            raise FileFormatError(f"array '{key}' has dtype {dtype}, not real numbers",
                                  file=src, column=key, fix=_NPZ_FIX)
        count = math.prod(shape)
        need = count * dtype.itemsize
        have = info.file_size - fh.tell()
        if need != have:  # check the declared shape against the bytes before allocating
            raise FileFormatError(f"array '{key}' declares shape {shape} ({need} bytes) but the "
                                  f"archive holds {have} bytes of it", file=src, column=key,
                                  fix="the file is damaged or truncated: write it again")
        data = fh.read(need)
        if len(data) != need or fh.read(1):  # reading to the end checks the CRC
            raise FileFormatError(f"array '{key}' is truncated ({len(data)} of {need} bytes)",
                                  file=src, column=key, fix="the file is damaged: write it again")
    arr = np.frombuffer(data, dtype=dtype, count=count)
    return arr.reshape(shape[::-1]).T if fortran else arr.reshape(shape)
