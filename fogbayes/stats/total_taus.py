"""Averaging factors of the total deviations and Theo1: each kind's largest valid m and
the named grids (``octave``, ``decade``, ``dense``, ``all``) cut to it (NIST SP 1065
sec. 5.2.11-5.2.15; Theo1 takes even m up to :func:`~fogbayes.stats.theo1.theo1_limit`)."""

from __future__ import annotations

import math

import numpy as np

from ..errors import TooShortError
from .taus import GRIDS, TauGridError
from .theo1 import theo1_limit


def total_limits(n: int, kind: str) -> tuple[int, int]:
    """(largest valid m, default top of a named grid) for ``n`` rate samples."""
    N = n + 1
    if kind == "totdev":
        return n, N // 2
    if kind == "mtotdev":
        return N // 3, N // 3
    if kind == "htotdev":
        return n // 3, n // 3
    top = theo1_limit(n)
    return top, top


def total_grid(n: int, taus="octave", kind: str = "totdev", *, m_max: int | None = None,
               per_decade: int = 20) -> tuple[int, ...]:
    """Averaging factors for ``n`` rate samples (module doc); Theo1 keeps even m only."""
    kind = "mtotdev" if kind == "ttotdev" else kind
    limit, top = total_limits(n, kind)
    lo = 2 if kind == "theo1" else 1
    if not isinstance(taus, str):
        ms = np.unique(np.asarray(taus, dtype=np.int64).reshape(-1))
        if ms.size == 0 or ms[0] < lo or ms[-1] > limit or (kind == "theo1" and (ms % 2).any()):
            what = "even averaging factors in" if kind == "theo1" else "averaging factors in"
            raise TooShortError(f"{kind} needs {what} {lo}..{limit} for {n} samples",
                                argument="taus", fix="pass smaller cluster sizes (samples, not s)")
        return tuple(int(m) for m in ms)
    top = min(top if m_max is None else int(m_max), limit)
    if top < lo:
        raise TooShortError(f"no {kind} averaging factor lies in {lo}..{top} ({n} samples)",
                            fix="record longer or raise m_max")
    if taus == "octave":
        ms = 2 ** np.arange(math.floor(math.log2(top)) + 1)
    elif taus == "decade":
        dec = 10 ** np.arange(math.floor(math.log10(top)) + 1)
        ms = np.concatenate([dec, 2 * dec, 4 * dec])
    elif taus == "dense":
        if int(per_decade) < 1:
            raise TauGridError(f"per_decade must be >= 1, got {per_decade}",
                               fix="pass per_decade=20 (or another positive integer)")
        k = np.arange(math.ceil(math.log10(top) * per_decade) + 1)
        ms = np.round(10.0 ** (k / per_decade))
        if kind == "theo1":
            ms = 2 * np.round(ms / 2)
    elif taus == "all":
        ms = np.arange(lo, top + 1, 2 if kind == "theo1" else 1)
    else:
        raise TauGridError(f"unknown tau grid '{taus}'", argument="taus",
                           fix=f"use one of {', '.join(GRIDS)} or explicit cluster sizes")
    ms = np.unique(ms.astype(np.int64))
    keep = (ms >= lo) & (ms <= top) & ((ms % 2 == 0) if kind == "theo1" else True)
    return tuple(int(m) for m in ms[keep])
