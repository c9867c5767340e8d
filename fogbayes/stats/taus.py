"""Averaging-time grids for the Allan family: cluster sizes ``m`` (tau = m / fs), as static tuples.

Grids: ``octave`` (1, 2, 4, ...), ``decade`` (1, 2, 4, 10, 20, 40, ...), ``dense``
(``per_decade`` log-spaced), ``all``; kinds ``oadev``, ``adev``, ``mdev``, ``ohdev``, ``hdev``.
Default ``m_max`` is Stable32's stop ratio: ``N // 4`` overlapping, ``N // 5`` non-overlapping.
"""

from __future__ import annotations

import numpy as np

from ..errors import FogbayesError, TooShortError

GRIDS = ("octave", "decade", "dense", "all")
#: Phase points per cluster at the largest tau (Stable32's stop ratio, by estimator).
STOP_RATIO = {"oadev": 4, "mdev": 4, "ohdev": 4, "adev": 5, "hdev": 5}
#: Differences needed per estimator: clusters spanned by one term (2 for Allan, 3 for Hadamard
#: and the modified Allan variance).
SPAN = {"oadev": 2, "adev": 2, "mdev": 3, "ohdev": 3, "hdev": 3}


class TauGridError(FogbayesError):
    """An unknown tau grid or an impossible cluster-size request."""


def max_cluster(n: int, kind: str = "oadev") -> int:
    """Largest sensible cluster size for ``n`` rate samples (Stable32 stop ratio)."""
    return max(1, (n + 1) // STOP_RATIO[_kind(kind)])


def cluster_sizes(n: int, grid: str = "octave", *, per_decade: int = 20,
                  m_max: int | None = None, kind: str = "oadev") -> tuple[int, ...]:
    """Sorted, unique cluster sizes ``m`` for ``n`` rate samples on the named grid.

    Args:
        n: number of rate samples (gaps included as NaN samples).
        grid: ``"octave"``, ``"decade"``, ``"dense"`` or ``"all"``.
        per_decade: points per decade for ``"dense"``.
        m_max: largest m (default :func:`max_cluster`); it is also capped so that at least one
            full term of the estimator fits in the record.
        kind: estimator (``oadev``, ``adev``, ``mdev``, ``ohdev``), for the defaults.
    """
    kind = _kind(kind)
    limit = (n + 1 - 1) // SPAN[kind]  # at least one term: span * m <= n
    top = max_cluster(n, kind) if m_max is None else int(m_max)
    top = min(top, limit)
    if top < 1:
        raise TooShortError(f"{n} samples are too few for any {kind} cluster",
                            fix=f"give at least {SPAN[kind] + 1} samples")
    if grid == "octave":
        ms = 2 ** np.arange(int(np.floor(np.log2(top))) + 1)
    elif grid == "decade":
        dec = 10 ** np.arange(int(np.floor(np.log10(top))) + 1)
        ms = np.concatenate([dec, 2 * dec, 4 * dec])
    elif grid == "dense":
        if int(per_decade) < 1:
            raise TauGridError(f"per_decade must be >= 1, got {per_decade}",
                               fix="pass per_decade=20 (or another positive integer)")
        k = np.arange(int(np.ceil(np.log10(top) * per_decade)) + 1)
        ms = np.round(10.0 ** (k / per_decade))
    elif grid == "all":
        ms = np.arange(1, top + 1)
    else:
        raise TauGridError(f"unknown tau grid '{grid}'", argument="taus",
                           fix=f"use one of {', '.join(GRIDS)}")
    ms = np.unique(ms.astype(np.int64))
    return tuple(int(m) for m in ms if 1 <= m <= top)


def _kind(kind: str) -> str:
    if kind not in STOP_RATIO:
        raise TauGridError(f"unknown deviation '{kind}'",
                           fix=f"use one of {', '.join(STOP_RATIO)}")
    return kind
