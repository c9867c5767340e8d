"""Test profiles: thermal-chamber programmes, lagging sensor temperatures, rate tables.

Programmes of ``Soak(temperature, duration)`` and ``Ramp(to, rate)`` (deg C/min). Sensors follow
tau dT_s/dt = T_chamber - T_s, exact for piecewise-linear input:
T_s[k+1] = a T_s[k] + (1 - c) u[k+1] + (c - a) u[k], a = exp(-h/tau), c = tau (1 - a)/h; their
rate is exact, (T_chamber - T_s)/tau (:func:`sensor_rates`).
"""

from __future__ import annotations

import math
from typing import NamedTuple, Sequence

import numpy as np

from ._checks import SimulationParameterError, positive, positive_int

#: The most samples one simulated record may have (8 bytes each, per column: 1.6 GB).
MAX_SAMPLES = 200_000_000


def _not_too_many(n: int, what: str) -> int:
    """Refuse a record that would exhaust memory, stating its size."""
    if n > MAX_SAMPLES:
        raise SimulationParameterError(
            f"{what} gives {n:.3g} samples ({n * 8 / 1e9:.3g} GB per column), more than the "
            f"{MAX_SAMPLES:.0e} a simulated record may have", column=what,
            fix="lower the duration or the sample rate fs")
    return n


class Soak(NamedTuple):
    """Hold the chamber at ``temperature`` (deg C) for ``duration`` s."""

    temperature: float
    duration: float


class Ramp(NamedTuple):
    """Move the chamber to ``to`` (deg C) at ``rate`` deg C/min (magnitude)."""

    to: float
    rate: float


class ThermalProfile(NamedTuple):
    """A thermal test: chamber temperature and lagging sensor channels on a uniform grid."""

    time: np.ndarray  # (n,) s from 0
    chamber: np.ndarray  # (n,) deg C
    temperatures: np.ndarray  # (n, k) sensor channels, deg C
    names: tuple[str, ...]  # channel names ("temperature", "temperature_2", ...)
    lags: tuple[float, ...]  # time constant of each channel, s
    rates: np.ndarray | None = None  # (n, k) exact dT/dt of each channel, deg C/min


class RateTableSchedule(NamedTuple):
    """Paper 000's rate-table test: every (temperature, rate) cell held for ``dwell`` s."""

    time: np.ndarray  # (n,) s from 0
    temperature: np.ndarray  # (n,) deg C (the gyro is soaked: sensor = chamber)
    input_rate: np.ndarray  # (n,) deg/s
    operating_time: np.ndarray  # (n,) s, the "t" of U1(T) t: restarts as set by ``restart``
    cell_temperature: np.ndarray  # (n,) int index into ``temperatures``
    cell_rate: np.ndarray  # (n,) int index into ``rates``
    temperatures: tuple[float, ...]
    rates: tuple[float, ...]


#: Paper 000's test grid (deg C and deg/s).
PAPER000_TEMPERATURES = (-30.0, -20.0, -10.0, -5.0, 0.0, 5.0, 10.0, 20.0, 40.0, 60.0)
PAPER000_RATES = (1.0, -1.0, 2.0, -2.0, 5.0, -5.0, 10.0, -10.0, 20.0, -20.0,
                  40.0, -40.0, 80.0, -80.0)


def time_grid(duration: float, fs: float) -> np.ndarray:
    """Uniform time stamps k / fs, k = 0 .. floor(duration fs) - 1 (s)."""
    n = positive_int(_not_too_many(
        int(math.floor(positive(duration, "duration") * positive(fs, "fs") + 1e-9)),
        "duration * fs"), "duration * fs")
    return np.arange(n) / fs


def as_segments(segments: Sequence) -> list:
    """Soak/Ramp segments from themselves or from their JSON form (see :func:`segments_json`)."""
    out = []
    for j, seg in enumerate(segments):
        if isinstance(seg, (Soak, Ramp)):
            out.append(seg)
        elif isinstance(seg, dict) and set(seg) == {"soak", "duration"}:
            out.append(Soak(float(seg["soak"]), float(seg["duration"])))
        elif isinstance(seg, dict) and set(seg) == {"ramp", "rate"}:
            out.append(Ramp(float(seg["ramp"]), float(seg["rate"])))
        else:
            raise SimulationParameterError(
                f"segment {j} is {seg!r}", argument="segments",
                fix='give Soak/Ramp or {"soak": deg_C, "duration": s} / '
                    '{"ramp": to_deg_C, "rate": deg_C_per_min}')
    if not out:
        raise SimulationParameterError("the programme has no segment", argument="segments",
                                       fix="give at least one Soak or Ramp")
    return out


def segments_json(segments: Sequence) -> list[dict]:
    """The JSON form of a programme: ``{"soak": T, "duration": s}``, ``{"ramp": to, "rate": r}``."""
    return [{"soak": s.temperature, "duration": s.duration} if isinstance(s, Soak)
            else {"ramp": s.to, "rate": s.rate} for s in as_segments(segments)]


def segment_knots(segments: Sequence, *, start: float) -> tuple[np.ndarray, np.ndarray]:
    """Knot times (s) and temperatures (deg C) of a piecewise-linear chamber programme."""
    times, temps = [0.0], [float(start)]
    for j, seg in enumerate(segments):
        if isinstance(seg, Soak):
            dt, to = positive(seg.duration, f"segment {j} duration", allow_zero=True), temps[-1]
            if seg.temperature != temps[-1]:
                raise SimulationParameterError(
                    f"segment {j} soaks at {seg.temperature} deg C but the chamber is at "
                    f"{temps[-1]} deg C", argument="segments",
                    fix="put a Ramp to the soak temperature before the Soak")
        elif isinstance(seg, Ramp):
            rate = positive(abs(seg.rate), f"segment {j} ramp rate")
            to = float(seg.to)
            dt = abs(to - temps[-1]) / rate * 60.0
        else:
            raise SimulationParameterError(f"segment {j} is {seg!r}", argument="segments",
                                           fix="use Soak(temperature, duration_s) or "
                                               "Ramp(to, rate_deg_C_per_min)")
        times.append(times[-1] + dt)
        temps.append(to)
    return np.asarray(times), np.asarray(temps)


def chamber_temperature(t: np.ndarray, segments: Sequence, *, start: float) -> np.ndarray:
    """Chamber temperature (deg C) at times ``t`` (held at the last value after the end)."""
    kt, kT = segment_knots(segments, start=start)
    return np.interp(np.asarray(t, dtype=float), kt, kT)


def chamber_rate(t: np.ndarray, segments: Sequence, *, start: float) -> np.ndarray:
    """Slope (deg C/min) of the piecewise-linear programme at times ``t``.

    0 before the start and after the end; at a knot (where the slope jumps) the mean of the
    slopes on either side, the derivative of the programme's linear interpolation there.
    """
    kt, kT = segment_knots(segments, start=start)
    span = np.diff(kt)
    slope = np.divide(np.diff(kT), span, out=np.zeros(span.size), where=span > 0)
    slope = np.concatenate([[0.0], slope, [0.0]])  # outside the programme: held, slope 0
    t = np.asarray(t, dtype=float)
    right = slope[np.searchsorted(kt, t, side="right")]
    left = slope[np.searchsorted(kt, t, side="left")]
    return 30.0 * (left + right)  # mean of the two sides, deg C/s -> deg C/min


def sensor_rates(temps: np.ndarray, chamber: np.ndarray, lags: Sequence[float],
                 chamber_slope: np.ndarray) -> np.ndarray:
    """Exact dT/dt (deg C/min) of lagged channels at their samples, (n, k).

    From the ODE itself, ``dT_s/dt = (T_chamber - T_s) / tau`` (deg C/s, times 60), which
    holds at each sample of :func:`first_order_lag`'s solution; a channel with tau = 0 is
    the chamber and takes ``chamber_slope`` (deg C/min, :func:`chamber_rate`).
    """
    temps = np.asarray(temps, dtype=float)
    out = np.empty(temps.shape)
    for j, tau in enumerate(lags):
        out[:, j] = chamber_slope if tau == 0 else 60.0 * (chamber - temps[:, j]) / tau
    return out


def first_order_lag(t: np.ndarray, u: np.ndarray, tau: float, *,
                    initial: float | None = None) -> np.ndarray:
    """Response of tau dy/dt = u - y, exact for u linear between samples
    (:func:`fogbayes.effects.lag.first_order_lag`, the loop's own lag filter).

    ``initial`` is y at t[0] (default u[0]: the sensor starts in equilibrium). tau = 0
    returns u itself.
    """
    from ..effects.lag import first_order_lag as lag

    return lag(t, u, positive(tau, "tau", allow_zero=True), initial=initial)


def thermal_profile(segments: Sequence, *, fs: float, start: float,
                    lags: Sequence[float] = (300.0, 900.0),
                    names: Sequence[str] | None = None,
                    duration: float | None = None) -> ThermalProfile:
    """Chamber programme -> chamber temperature, one lagging sensor channel per lag, and
    each channel's exact rate (:func:`sensor_rates`).

    ``duration`` defaults to the programme's length. Channel names default to the file
    contract: ``temperature``, ``temperature_2``, ...
    """
    kt, _ = segment_knots(segments, start=start)
    t = time_grid(kt[-1] if duration is None else duration, fs)
    ch = chamber_temperature(t, segments, start=start)
    lags = tuple(float(x) for x in lags)
    temps = np.stack([first_order_lag(t, ch, tau) for tau in lags], axis=1) if lags \
        else np.zeros((t.size, 0))
    if names is None:
        names = tuple("temperature" if j == 0 else f"temperature_{j + 1}" for j in range(len(lags)))
    if len(names) != len(lags):
        raise SimulationParameterError(f"{len(names)} names for {len(lags)} lags",
                                       argument="names", fix="give one name per lag")
    rates = sensor_rates(temps, ch, lags, chamber_rate(t, segments, start=start))
    return ThermalProfile(t, ch, temps, tuple(names), lags, rates)


def paper004_segments(*, room: float = 20.0, cold: float = -40.0, hot: float = 60.0,
                      soak: float = 7200.0, ramp_rate: float = 0.5) -> list:
    """Paper 004's verification programme: room, cold, hot, room; ``soak`` s each, ramps at
    ``ramp_rate`` deg C/min (2 h and 0.5 deg C/min in the paper; shorten both for tests)."""
    return [Soak(room, soak), Ramp(cold, ramp_rate), Soak(cold, soak), Ramp(hot, ramp_rate),
            Soak(hot, soak), Ramp(room, ramp_rate), Soak(room, soak)]


def paper004_profile(*, fs: float = 1.0, soak: float = 7200.0, ramp_rate: float = 0.5,
                     lags: Sequence[float] = (300.0, 900.0), **temps) -> ThermalProfile:
    """The verification profile of paper 004 (14.7 h at the paper's settings)."""
    segs = paper004_segments(soak=soak, ramp_rate=ramp_rate, **temps)
    return thermal_profile(segs, fs=fs, start=segs[0].temperature, lags=lags)


#: Generic thermal test (fractions of the total time): room soak, cool, cold soak, heat,
#: hot soak, cool back, room soak. At 6.3 h: ramps of 1 deg C/min between -20 and 60 deg C.
_GENERIC = ((0.0794, None), (0.1058, "low"), (0.1587, None), (0.2116, "high"),
            (0.1587, None), (0.1058, "room"), (0.1800, None))


def thermal_test_segments(*, duration: float = 6.3 * 3600.0, room: float = 20.0,
                          low: float = -20.0, high: float = 60.0) -> list:
    """A generic heating-and-cooling test lasting ``duration`` s (default 6.3 h).

    Segment durations scale with ``duration`` (ramp rates scale inversely), so shortened
    tests reach the same temperatures: it always heats and cools, soaks at three levels.
    """
    duration = positive(duration, "duration")
    level = {"low": low, "high": high, "room": room}
    segs, T = [], float(room)
    for frac, to in _GENERIC:
        dt = frac * duration
        if to is None:
            segs.append(Soak(T, dt))
        else:
            segs.append(Ramp(level[to], abs(level[to] - T) / (dt / 60.0)))
            T = level[to]
    return segs


def thermal_test_profile(*, fs: float = 10.0, duration: float = 6.3 * 3600.0,
                         lags: Sequence[float] = (300.0, 900.0), **levels) -> ThermalProfile:
    """The generic 6.3 h thermal test (see :func:`thermal_test_segments`) at ``fs`` Hz."""
    segs = thermal_test_segments(duration=duration, **levels)
    return thermal_profile(segs, fs=fs, start=segs[0].temperature, lags=lags, duration=duration)


def rate_table_schedule(*, fs: float = 1.0, dwell: float = 60.0,
                        temperatures: Sequence[float] = PAPER000_TEMPERATURES,
                        rates: Sequence[float] = PAPER000_RATES,
                        restart: str = "cell") -> RateTableSchedule:
    """Paper 000's grid: for each temperature, each rate held ``dwell`` s (10 x 14 cells).

    The gyro is taken as soaked at each temperature (the model is static). The operating
    time t of the U1(T) t term restarts at each cell (``restart="cell"``, matching the
    per-cell fit U_ij = A_ij + B_ij t of eq. 10), at each temperature (``"temperature"``),
    or never (``"run"``: t = time).
    """
    fs, dwell = positive(fs, "fs"), positive(dwell, "dwell")
    per = positive_int(int(round(dwell * fs)), "dwell * fs")
    nT, nW = len(temperatures), len(rates)
    if nT == 0 or nW == 0:
        raise SimulationParameterError("the rate table needs at least one temperature and rate",
                                       argument="temperatures", fix="give non-empty grids")
    k = np.arange(_not_too_many(nT * nW * per, "dwell * fs * cells"))
    cell = k // per
    iT, iW = cell // nW, cell % nW
    if restart == "cell":
        op = (k % per) / fs
    elif restart == "temperature":
        op = (k % (per * nW)) / fs
    elif restart == "run":
        op = k / fs
    else:
        raise SimulationParameterError(f"unknown restart {restart!r}", argument="restart",
                                       fix="use 'cell', 'temperature' or 'run'")
    Tg, Wg = np.asarray(temperatures, float), np.asarray(rates, float)
    return RateTableSchedule(k / fs, Tg[iT], Wg[iW], op, iT, iW,
                             tuple(map(float, Tg)), tuple(map(float, Wg)))
