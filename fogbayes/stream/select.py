"""Exact order statistics (medians) of a value stream too large to hold: radix selection.

key(x) = bits(x) | 2^63 (x >= 0), ~bits(x) (x < 0) orders like x; each pass histograms the next
16 bits among keys sharing the found prefix (at most four passes). Equals ``np.median``; memory
O(65 536) per rank.
"""

from __future__ import annotations

from typing import Callable, Iterable

import numpy as np

_DIGIT = 16
_SIGN = np.uint64(1 << 63)


def order_keys(x: np.ndarray) -> np.ndarray:
    """uint64 keys ordered as the float64 values ``x`` (module doc)."""
    b = np.ascontiguousarray(x, dtype=np.float64).view(np.uint64)
    return np.where(b & _SIGN, ~b, b | _SIGN)


def _value(key: int) -> float:
    k = np.array([key], np.uint64)
    b = np.where(k & _SIGN, k & ~_SIGN, ~k)
    return float(b.view(np.float64)[0])


def order_statistics(passes: Callable[[], Iterable[np.ndarray]],
                     ranks: list[int]) -> tuple[dict[int, float], int]:
    """The values of 0-based ``ranks`` in the sorted stream, and the passes made.

    ``passes()`` starts a new pass and yields the stream's values in float64 arrays.
    """
    state = {r: (0, 0, r) for r in ranks}  # rank -> (prefix, prefix bits, rank inside)
    found: dict[int, float] = {}
    n_passes = 0
    while len(found) < len(ranks):
        todo = {(p, bits) for r, (p, bits, _) in state.items() if r not in found}
        hist = {key: np.zeros(1 << _DIGIT, np.int64) for key in todo}
        lo = {key: np.inf for key in todo}
        hi = {key: -np.inf for key in todo}
        n_passes += 1
        for x in passes():
            x = np.asarray(x, dtype=np.float64)
            if not x.size:
                continue
            k = order_keys(x)
            for (p, bits) in todo:
                shift = np.uint64(64 - bits - _DIGIT)
                if bits:
                    inside = (k >> np.uint64(64 - bits)) == np.uint64(p)
                    sel, v = k[inside], x[inside]
                else:
                    sel, v = k, x
                if sel.size:
                    digit = ((sel >> shift) & np.uint64(0xFFFF)).astype(np.int64)
                    hist[p, bits] += np.bincount(digit, minlength=1 << _DIGIT)
                    lo[p, bits] = min(lo[p, bits], float(v.min()))
                    hi[p, bits] = max(hi[p, bits], float(v.max()))
        for r, (p, bits, k) in list(state.items()):
            if r in found:
                continue
            if lo[p, bits] == hi[p, bits]:  # every value in this bucket is equal
                found[r] = lo[p, bits]
                continue
            cum = np.cumsum(hist[p, bits])
            d = int(np.searchsorted(cum, k, side="right"))
            k -= int(cum[d - 1]) if d else 0
            p, bits = (p << _DIGIT) | d, bits + _DIGIT
            if bits == 64:
                found[r] = _value(p)
            state[r] = (p, bits, k)
    return found, n_passes


def stream_median(passes: Callable[[], Iterable[np.ndarray]], n: int) -> tuple[float, int]:
    """``np.median`` of the ``n`` values the passes yield, and the passes made."""
    ranks = sorted({(n - 1) // 2, n // 2})
    found, made = order_statistics(passes, ranks)
    if len(ranks) == 2:
        return float((found[ranks[0]] + found[ranks[1]]) / 2.0), made
    return float(found[ranks[0]]), made
