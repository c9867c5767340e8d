"""The Recording: the one data type that flows through fogbayes (frozen, read-only float64 arrays).

``time`` (n,) s, increasing, gaps allowed; ``output`` (n,) in ``unit`` (deg/h, deg/s, rad/s, or
raw with ``scale_factor`` per deg/s); ``temperatures`` (n, k) deg C, ``temperature_names``;
``input_rate`` (n,) deg/s or None; ``meta``.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any, NamedTuple

import numpy as np

from ..errors import (EmptyRecordingError, NonFiniteError, ShapeError, TimeOrderError, TooShortError,
                      UnitError)
from .units import convert_rate, normalise_unit


@dataclass(frozen=True)
class Metadata:
    """Descriptive information that travels with a Recording."""

    sensor_id: str = "unknown"
    sample_rate: float | None = None  # nominal, Hz; None = estimate from time
    source: str | None = None  # file the data came from
    extra: dict[str, Any] = field(default_factory=dict)


class Gap(NamedTuple):
    """A gap in sampling: samples ``index - 1`` and ``index`` are ``duration`` s apart."""

    index: int
    start: float
    duration: float


class SamplingReport(NamedTuple):
    """How regular the sampling is."""

    n: int
    duration: float  # s, last minus first time stamp
    dt_median: float  # s
    sample_rate: float  # Hz, 1 / dt_median
    irregular: bool  # dt varies by more than 1 % (outside gaps)
    gaps: tuple[Gap, ...]  # intervals longer than 1.5 x the median step


def _scale_factor(value, src: str | None) -> float:
    """A scale factor (raw units per deg/s) must be a finite number > 0."""
    try:
        sf = float(value)
    except (TypeError, ValueError):
        sf = float("nan")
    if isinstance(value, bool) or not np.isfinite(sf) or sf <= 0:
        raise UnitError(f"scale factor {value!r} is not a finite number > 0", file=src,
                        column="scale_factor",
                        fix="give the raw units per deg/s, e.g. --scale-factor 0.04 for "
                            "40 mV/(deg/s)")
    return sf


def _frozen(a: np.ndarray) -> np.ndarray:
    a = np.array(a, dtype=float, copy=True)
    a.setflags(write=False)
    return a


@dataclass(frozen=True, eq=False)
class Recording:
    """A gyro recording with its time base, temperatures, reference rate and metadata.

    Example:
        >>> import numpy as np
        >>> rec = Recording(time=np.arange(5.0), output=np.zeros(5), unit="deg/h")
        >>> rec.n, rec.sampling().sample_rate
        (5, 1.0)
    """

    time: np.ndarray
    output: np.ndarray
    unit: str = "deg/h"
    temperatures: np.ndarray | None = None
    temperature_names: tuple[str, ...] = ()
    input_rate: np.ndarray | None = None
    scale_factor: float | None = None
    meta: Metadata = field(default_factory=Metadata)

    def __post_init__(self):
        src = self.meta.source
        time = _frozen(np.ravel(self.time))
        output = _frozen(np.ravel(self.output))
        n = time.size
        if n == 0:
            raise EmptyRecordingError("the recording has no samples", file=src,
                                      fix="give at least two rows of data")
        if output.shape != (n,):
            raise ShapeError(f"output has {output.size} samples but time has {n}", file=src,
                             column="output", fix="give one output value per time stamp")
        temps = self.temperatures
        if temps is None:
            temps = np.zeros((n, 0))
        temps = np.asarray(temps, dtype=float)
        if temps.ndim == 1:
            temps = temps[:, None]
        if temps.shape[0] != n:
            raise ShapeError(f"temperatures have {temps.shape[0]} rows but time has {n}",
                             file=src, column="temperature",
                             fix="give one temperature row per time stamp")
        names = tuple(self.temperature_names) or default_temperature_names(temps.shape[1])
        if len(names) != temps.shape[1]:
            raise ShapeError(f"{len(names)} temperature names for {temps.shape[1]} channels",
                             file=src, column="temperature", fix="name every channel once")
        rate = self.input_rate
        if rate is not None:
            rate = _frozen(np.ravel(rate))
            if rate.shape != (n,):
                raise ShapeError(f"input_rate has {rate.size} samples but time has {n}",
                                 file=src, column="input_rate",
                                 fix="give one input rate per time stamp")
        object.__setattr__(self, "time", time)
        object.__setattr__(self, "output", output)
        object.__setattr__(self, "temperatures", _frozen(temps))
        object.__setattr__(self, "temperature_names", names)
        object.__setattr__(self, "input_rate", rate)
        object.__setattr__(self, "unit", normalise_unit(self.unit, file=src))
        if self.scale_factor is not None:
            object.__setattr__(self, "scale_factor", _scale_factor(self.scale_factor, src))
        self._validate()

    # -- validation -------------------------------------------------------------------
    def _validate(self) -> None:
        src = self.meta.source
        columns = [("time", self.time), ("output", self.output)]
        columns += [(nm, self.temperatures[:, j]) for j, nm in enumerate(self.temperature_names)]
        if self.input_rate is not None:
            columns.append(("input_rate", self.input_rate))
        for name, col in columns:
            bad = np.flatnonzero(~np.isfinite(col))
            if bad.size:
                raise NonFiniteError(
                    f"{bad.size} value(s) are NaN, empty or infinite (first: {col[bad[0]]})",
                    file=src, column=name, row=int(bad[0]),
                    fix="remove or repair those rows; fogbayes never fills gaps silently",
                )
        dt = np.diff(self.time)
        bad = np.flatnonzero(dt <= 0)
        if bad.size:
            r = int(bad[0]) + 1
            what = "repeats" if dt[bad[0]] == 0 else "goes back from"
            raise TimeOrderError(
                f"time {what} the previous row ({float(self.time[r - 1])!r} -> "
                f"{float(self.time[r])!r})",
                file=src, column="time", row=r,
                fix="sort the rows by time and remove duplicate time stamps",
            )

    # -- views ------------------------------------------------------------------------
    @property
    def n(self) -> int:
        return int(self.time.size)

    @property
    def temperature(self) -> np.ndarray:
        """The first temperature channel (deg C)."""
        if self.temperatures.shape[1] == 0:
            raise TooShortError("the recording has no temperature channel",
                                file=self.meta.source, column="temperature",
                                fix="add a 'temperature' column in deg C")
        return self.temperatures[:, 0]

    @property
    def has_temperature(self) -> bool:
        return self.temperatures.shape[1] > 0

    def channel(self, name: str) -> np.ndarray:
        """A temperature channel by name."""
        if name not in self.temperature_names:
            raise TooShortError(f"no temperature channel named '{name}'",
                                file=self.meta.source, column=name,
                                fix=f"use one of {list(self.temperature_names)}")
        return self.temperatures[:, self.temperature_names.index(name)]

    def rate(self, unit: str = "deg/h") -> np.ndarray:
        """The output as an angular rate in ``unit`` (raw outputs divided by the scale factor)."""
        return convert_rate(self.output, self.unit, unit, scale_factor=self.scale_factor)

    def sampling(self) -> SamplingReport:
        """Sample rate, regularity and gaps (never filled)."""
        if self.n < 2:
            return SamplingReport(self.n, 0.0, float("nan"), float("nan"), False, ())
        dt = np.diff(self.time)
        med = float(np.median(dt))
        gap_idx = np.flatnonzero(dt > 1.5 * med)
        gaps = tuple(Gap(int(i) + 1, float(self.time[i]), float(dt[i])) for i in gap_idx)
        inside = np.delete(dt, gap_idx)
        irregular = bool(inside.size and np.max(np.abs(inside - med)) > 0.01 * med)
        return SamplingReport(self.n, float(self.time[-1] - self.time[0]), med, 1.0 / med,
                              irregular, gaps)

    @property
    def sample_rate(self) -> float:
        """Nominal sample rate (Hz): from metadata, else from the median time step."""
        if self.meta.sample_rate:
            return float(self.meta.sample_rate)
        return self.sampling().sample_rate

    def require(self, n_min: int, what: str) -> None:
        """Raise :class:`TooShortError` unless the recording has at least ``n_min`` samples."""
        if self.n < n_min:
            raise TooShortError(
                f"{what} needs at least {n_min} samples, the recording has {self.n}",
                file=self.meta.source, fix="record longer or ask for less (e.g. fewer tau values)",
            )

    def replace(self, **changes) -> "Recording":
        """A copy with some fields changed (validated again)."""
        return dataclasses.replace(self, **changes)

    def slice(self, start: int, stop: int) -> "Recording":
        """Rows ``start:stop`` as a new Recording."""
        sl = slice(start, stop)
        return self.replace(
            time=self.time[sl], output=self.output[sl],
            temperatures=self.temperatures[sl],
            input_rate=None if self.input_rate is None else self.input_rate[sl],
        )

    def __repr__(self) -> str:
        s = self.sampling()
        temps = ", ".join(self.temperature_names) or "none"
        return (f"Recording(sensor={self.meta.sensor_id!r}, n={self.n}, "
                f"duration={s.duration:.1f} s, fs={s.sample_rate:.4g} Hz, unit={self.unit!r}, "
                f"temperatures=[{temps}], input_rate={'yes' if self.input_rate is not None else 'no'}, "
                f"gaps={len(s.gaps)})")


def default_temperature_names(k: int) -> tuple[str, ...]:
    """``temperature``, ``temperature_2``, ``temperature_3``, ... (the file contract)."""
    return tuple("temperature" if j == 0 else f"temperature_{j + 1}" for j in range(k))
