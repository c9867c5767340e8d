"""``fogbayes.support.numba_cache.over_rows``: rows split over threads, each row run exactly once."""

import numba as nb
import numpy as np
import pytest

from fogbayes.support.numba_cache import numba, over_rows


@numba.njit(nogil=True)
def _mark(r0, r1, hits, first):
    for r in range(r0, r1):
        hits[r] += 1
        first[r] = r0


@numba.njit(nogil=True, error_model="python")
def _divide(r0, r1, x, out):
    for r in range(r0, r1):
        out[r] = 1 // int(x[r])  # raises ZeroDivisionError at x == 0


@pytest.mark.parametrize("n_rows", [1, 2, 3, 7, 8, 1001])
def test_every_row_once_in_contiguous_ranges(n_rows):
    hits, first = np.zeros(n_rows, np.int64), np.full(n_rows, -1, np.int64)
    over_rows(_mark, n_rows, hits, first)
    assert np.all(hits == 1)
    starts = np.unique(first)  # one range per thread, at most Numba's thread count
    assert starts[0] == 0 and len(starts) <= max(1, min(nb.get_num_threads(), n_rows))
    assert np.all(np.diff(first) >= 0)  # contiguous: a range's rows share its start


def test_few_rows_run_in_one_call():
    hits, first = np.zeros(5, np.int64), np.full(5, -1, np.int64)
    over_rows(_mark, 5, hits, first, min_rows=8)
    assert np.all(hits == 1) and np.all(first == 0)


def test_a_kernels_error_reaches_the_caller():
    x = np.ones(64)
    x[40] = 0.0  # in the last thread's range when there are two or more
    with pytest.raises(ZeroDivisionError):
        over_rows(_divide, 64, x, np.zeros(64, np.int64))
