"""The CSV reader's NumPy path (:func:`fogbayes.data._read.numeric_columns`, taken where pandas
is not loaded yet) gives what pandas' C parser gives: the same dtype per column (int64 where
every field is an integer, float64 otherwise) and the same bits, or None -- and pandas reads
the body -- where a field is anything else."""

from __future__ import annotations

import io

import numpy as np
import pandas as pd
import pytest

from fogbayes.data._read import numeric_columns


def _pandas(body: bytes, n: int, sep: str) -> list[np.ndarray]:
    df = pd.read_csv(io.BytesIO(body), header=None, names=[f"c{k}" for k in range(n)],
                     index_col=False, sep=sep, skipinitialspace=True, skip_blank_lines=False,
                     low_memory=False, encoding="utf-8")
    return [df[f"c{k}"].to_numpy() for k in range(n)]


def _same(ours, theirs):
    assert len(ours) == len(theirs)
    for a, b in zip(ours, theirs):
        assert a.dtype == b.dtype
        assert a.flags.c_contiguous
        np.testing.assert_array_equal(a, b, strict=True)


def _field(rng, kind: str) -> str:
    v = float(rng.standard_normal() * 10.0 ** rng.integers(-12, 12))
    if kind == "repr":
        return repr(v)
    if kind == "g9":
        return f"{v:.9g}"
    if kind == "e":
        return f"{v:+.12E}"
    if kind == "f":
        return f"{v:.6f}"
    if kind == "long":  # 25 significant digits: the parsers must both round correctly
        digits = "".join(map(str, rng.integers(0, 10, 25)))
        return f"{'-' if rng.random() < 0.5 else ''}{digits[0]}.{digits[1:]}e{rng.integers(-30, 30)}"
    if kind == "int":
        return str(int(rng.integers(-10 ** 6, 10 ** 6)))
    if kind == "big":  # integers past 2^53: int64 exact, not through a float
        return str(int(rng.integers(2 ** 60, 2 ** 62)))
    if kind == "spaced":
        return f" {int(rng.integers(-99, 99)):+d} "
    raise ValueError(kind)


@pytest.mark.parametrize("sep", [",", ";", "\t"])
@pytest.mark.parametrize("seed", range(4))
def test_numbers_read_as_pandas_reads_them(sep, seed):
    rng = np.random.default_rng(seed)
    kinds = ["repr", "g9", "e", "f", "long", "int", "big", "spaced"]
    cols = [kinds[k % len(kinds)] for k in rng.permutation(12)]
    rows = [sep.join(_field(rng, k) for k in cols) for _ in range(300)]
    body = ("\n".join(rows) + "\n").encode()
    ours = numeric_columns(body, len(cols), sep)
    assert ours is not None
    theirs = _pandas(body, len(cols), sep)
    _same(ours, theirs)
    assert [a.dtype.kind for a in ours] == ["i" if k in ("int", "big", "spaced") else "f"
                                           for k in cols]


def test_an_integer_column_with_one_decimal_point_is_float():
    body = b"0,1\n1,2.0\n2,3\n"
    ours = numeric_columns(body, 2, ",")
    _same(ours, _pandas(body, 2, ","))
    assert [a.dtype for a in ours] == [np.int64, np.float64]


@pytest.mark.parametrize("body", [
    b"1,\n2,3\n",              # an empty field: pandas makes it NaN
    b"1,NA\n2,3\n",            # a missing-value marker
    b"1,nan\n2,3\n",           # NaN spelt out (NumPy also takes 'nAn', pandas keeps text)
    b"1,nAn\n2,3\n",
    b"1,inf\n2,3\n",
    b"1,1_000\n2,3\n",         # text to pandas, text to us
    b"1,0x10\n2,3\n",
    b"1,1.5.2\n2,3\n",
    b"1,9223372036854775808\n2,3\n",  # past int64: pandas makes uint64
    b"1,1e400\n2,3\n",         # overflows to inf
    b"1,\xc3\xa9\n2,3\n",
    b"1,-\n2,3\n",
])
def test_anything_but_a_number_is_left_to_pandas(body):
    assert numeric_columns(body, 2, ",") is None


def test_a_field_count_other_than_the_header_is_left_to_pandas():
    assert numeric_columns(b"1,2,3\n4,5,6\n", 2, ",") is None


def test_a_separator_beyond_ascii_is_left_to_pandas():
    assert numeric_columns("1§2\n3§4\n".encode(), 2, "§") is None
