"""Rate-table recordings as (T_i, W_j) cells for the composite model (paper 000).

:func:`rate_data` finds the cells (:func:`fogbayes.preprocess.segment_rate_table` or a user
schedule) and gives each sample its operating time t (:mod:`fogbayes.preprocess.operating_time`:
``"cell"``, ``"temperature"`` or ``"run"``). :func:`summarise_cells` reduces each cell to its
line in t, A_ij = mean - slope * t-mean, B_ij = slope (eq. 10).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..data.recording import Recording
from ..errors import MissingColumnError, TooShortError
from ..preprocess.operating_time import check_convention, operating_time


class RateData(NamedTuple):
    """In-cell samples of a rate-table run (m samples, K cells, n_T x n_W levels)."""

    U: np.ndarray  # (m,) output, recording unit
    T: np.ndarray  # (m,) deg C, measured
    W: np.ndarray  # (m,) deg/s, reference input rate
    t: np.ndarray  # (m,) s, operating time
    cell: np.ndarray  # (m,) int, 0..K-1
    row: np.ndarray  # (m,) int, row in the recording
    time: np.ndarray  # (m,) s, absolute time stamps (orders the cells in time)
    cell_i: np.ndarray  # (K,) temperature level of each cell
    cell_j: np.ndarray  # (K,) rate level of each cell
    temperature_levels: np.ndarray  # (n_T,) deg C
    rate_levels: np.ndarray  # (n_W,) deg/s


class CellSummary(NamedTuple):
    """Per-cell least-squares line U = mean + slope (t - t_mean) (all (K,))."""

    n: np.ndarray
    t_mean: np.ndarray
    mean: np.ndarray
    slope: np.ndarray
    Sxx: np.ndarray
    rss: np.ndarray
    T: np.ndarray  # mean temperature of the cell
    W: np.ndarray  # mean input rate of the cell

    @property
    def intercept(self) -> np.ndarray:
        """A_ij of eq. 10: the line at t = 0."""
        return self.mean - self.slope * self.t_mean




def rate_data(rec: Recording, *, convention: str = "cell", schedule=None, table=None,
              **segment_options) -> tuple[RateData, object]:
    """Split a rate-table Recording into cells; returns (RateData, the RateTable used).

    Args:
        rec: needs ``input_rate`` (deg/s) and a temperature channel (its first is used).
        convention: operating-time convention ("cell", "temperature", "run").
        schedule: optional [(t_start, t_stop, T, W), ...] replacing plateau detection.
        table: a ready :class:`fogbayes.preprocess.RateTable` (skips detection).
        **segment_options: passed to :func:`fogbayes.preprocess.segment_rate_table`.
    """
    from ..preprocess import segment_rate_table

    src = rec.meta.source
    if rec.input_rate is None and schedule is None and table is None:
        raise MissingColumnError("the composite model needs the reference input rate",
                                 file=src, column="input_rate",
                                 fix="add an 'input_rate' column (deg/s) from the rate table")
    if not rec.has_temperature:
        raise MissingColumnError("the composite model needs a temperature channel", file=src,
                                 column="temperature", fix="add a 'temperature' column in deg C")
    check_convention(convention)
    if table is None:
        table = segment_rate_table(rec.time, rec.input_rate, rec.temperature,
                                   schedule=schedule, **segment_options)
    if len(table.cells) < 2:
        raise TooShortError(f"found {len(table.cells)} rate-table cell(s)", file=src,
                            column="input_rate", fix="record several rates and temperatures")
    W_all = rec.input_rate if rec.input_rate is not None else _nominal_rate(rec.n, table)
    tol = float(segment_options.get("rate_tolerance", 0.01))
    t_all = operating_time(rec.time, W_all, table.cells, convention=convention, rate_tolerance=tol)
    rows = np.concatenate([np.arange(c.start, c.stop) for c in table.cells])
    cell = np.concatenate([np.full(c.stop - c.start, k) for k, c in enumerate(table.cells)])
    data = RateData(U=np.asarray(rec.output[rows], float), T=np.asarray(rec.temperature[rows]),
                    W=np.asarray(W_all[rows], float), t=t_all[rows], cell=cell, row=rows,
                    time=np.asarray(rec.time[rows]),
                    cell_i=np.array([c.i for c in table.cells]),
                    cell_j=np.array([c.j for c in table.cells]),
                    temperature_levels=np.asarray(table.temperature_levels, float),
                    rate_levels=np.asarray(table.rate_levels, float))
    return data, table


def _nominal_rate(n: int, table) -> np.ndarray:
    """Scheduled rates on the cells (used when the file has no input_rate column)."""
    W = np.zeros(n)
    for c in table.cells:
        W[c.start:c.stop] = c.rate
    return W


def summarise_cells(data: RateData) -> CellSummary:
    """Per-cell OLS line in t, vectorised (no Python loop over cells)."""
    K = int(data.cell.max()) + 1
    cnt = np.bincount(data.cell, minlength=K).astype(float)
    if np.any(cnt < 3):
        bad = int(np.flatnonzero(cnt < 3)[0])
        raise TooShortError(f"cell {bad} has {int(cnt[bad])} sample(s); a line needs 3",
                            column="input_rate", fix="hold each rate longer (or lower trim_s)")
    mean_of = lambda x: np.bincount(data.cell, x, K) / cnt  # noqa: E731
    tm, um = mean_of(data.t), mean_of(data.U)
    dt, du = data.t - tm[data.cell], data.U - um[data.cell]
    sxx = np.bincount(data.cell, dt * dt, K)
    sxy = np.bincount(data.cell, dt * du, K)
    # a cell whose time does not vary (one instant) gives no slope: treat it as 0
    slope = np.where(sxx > 0, sxy / np.where(sxx > 0, sxx, 1.0), 0.0)
    rss = np.bincount(data.cell, (du - slope[data.cell] * dt) ** 2, K)
    return CellSummary(cnt, tm, um, slope, sxx, rss, mean_of(data.T), mean_of(data.W))
