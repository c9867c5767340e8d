"""``fogbayes plan-chamber``: which chamber programme lets the loop tell a lag from a gradient.

Thin layer over :func:`fogbayes.plan.programme.plan_programme` (docs/plan.md, "Which chamber
programme"): the noise model from a pilot chamber recording (or from Allan terms), the
candidate programmes scored by how far each true effect lies from its rival, and the best
one printed beside the baseline with the duel's predicted power for every pair.
"""

from __future__ import annotations

import sys
from pathlib import Path

import typer

from ._app import app
from ._common import (QUIET_OPT, TIME_UNIT_OPT, load_recording, progress, refuse_overwrite,
                      say, write_json)


def _floats(text: str, flag: str, n: int | None = None) -> list[float]:
    from ..errors import ArgumentError

    try:
        out = [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        out = []
    if not out or (n is not None and len(out) != n):
        want = f"{n} comma-separated numbers" if n else "comma-separated numbers"
        raise ArgumentError(f"{flag} {text!r} is not {want}", column=flag,
                            fix=f"e.g. {flag} " + {"--noise": "0.005,0.02,0.02",
                                                   "--lags": "300,900"}.get(flag, "1800"))
    return out


def _segments_file(path: Path) -> list:
    from ..errors import ArgumentError
    from ..simulate._checks import SimulationParameterError
    from ..simulate.profiles import as_segments

    from ..data.json_file import read_json_file

    fix = ('give a JSON list such as [{"soak": 20, "duration": 600}, {"ramp": 60, "rate": 2}, '
           '...] (deg C, s, deg C/min)')
    doc = read_json_file(path, "the --programme file", fix)
    try:
        segs = doc["segments"] if isinstance(doc, dict) else doc
        return as_segments(segs)
    except (ValueError, KeyError, TypeError, SimulationParameterError) as exc:
        raise ArgumentError(f"cannot read a programme from {path}: {exc}", column="--programme",
                            fix=fix) from None


def _lines(doc: dict) -> list[str]:
    b, a = doc["baseline"], doc["best"]
    s = doc["settings"]
    out = [f"plan-chamber: {s['duration_s'] / 3600:.3g} h at {s['fs_hz']:g} Hz, "
           f"{s['low']:g}..{s['high']:g} deg C, ramps <= {s['max_rate_deg_c_per_min']:g} "
           f"deg C/min, channels lag {', '.join(f'{v:g}' for v in s['lags_s'])} s; "
           f"noise from {s['noise_from']}",
           f"  best programme: {a['name']}",
           "  " + " -> ".join(_seg(g) for g in a["segments"]),
           f"  compared with (before): {b['name']}",
           f"  {'pair':58s} {'noncentrality':>21s} {'P(duel rejects the rival)':>26s}",
           f"  {'':58s} {'before':>10s} {'best':>10s}  {'before':>11s} {'best':>10s}"]
    for lab in a["noncentrality"]:
        pw = lambda d: "-" if d["power"][lab] is None else f"{d['power'][lab]:.3f}"
        out.append(f"  {lab:58s} {b['noncentrality'][lab]:10.3g} {a['noncentrality'][lab]:10.3g}"
                   f"  {pw(b):>11s} {pw(a):>10s}")
    if min(a["noncentrality"].values()) <= min(b["noncentrality"].values()):
        out.append(f"  no searched cycle separates the pairs better than {b['name']}: keep it")
    weak = [lab for lab, p in a["power"].items() if p is not None and p < 0.8]
    if weak:
        out.append(f"  warning: even the best programme leaves {', '.join(weak)} below 0.8: "
                   "record longer, or the effect is smaller than the loop can attribute")
    return out


def _seg(g: dict) -> str:
    if "soak" in g:
        return f"soak {g['soak']:g} C {g['duration'] / 60:.3g} min"
    return f"ramp to {g['ramp']:g} C at {g['rate']:g} C/min"


@app.command("plan-chamber")
def plan_chamber(
    pilot: Path = typer.Argument(None, help="A chamber recording of the sensor (noise model, "
                                            "length and rate of the plan); omit with --noise.",
                                 show_default=False),
    noise: str = typer.Option(None, "--noise", help="Without a pilot: Allan terms N,B,K "
                              "(deg/sqrt(h), deg/h, deg/h^1.5), e.g. 0.005,0.02,0.02.",
                              show_default=False),
    hours: float = typer.Option(3.0, "--hours", help="Record length without a pilot (h)."),
    fs: float = typer.Option(10.0, "--fs", help="Sample rate without a pilot (Hz)."),
    lags: str = typer.Option("300,900", "--lags", help="Time constants (s) with which the two "
                                                       "temperature channels follow the chamber."),
    low: float = typer.Option(-20.0, "--low", help="Lowest chamber temperature (deg C)."),
    high: float = typer.Option(60.0, "--high", help="Highest chamber temperature (deg C)."),
    room: float = typer.Option(20.0, "--room", help="Start temperature (deg C)."),
    max_rate: float = typer.Option(5.0, "--max-rate", help="Fastest ramp the chamber can do "
                                                           "(deg C/min)."),
    lag_tau: str = typer.Option("1800", "--lag-tau", help="True lag time constant(s) to plan "
                                                          "for (s, comma-separated)."),
    lag_coeff: float = typer.Option(0.01, "--lag-coeff", help="Lag coefficient to plan for "
                                                              "(deg/h per deg C)."),
    rate_coeff: float = typer.Option(0.3, "--rate-coeff", help="Shupe coefficient to plan for "
                                                               "(deg/h per deg C/min)."),
    programme: Path = typer.Option(None, "--programme", help="Your current programme (JSON "
                                   "segments) as the baseline; default the generic test.",
                                   show_default=False),
    json_out: str = typer.Option(None, "--json", help="Also write the plan ('-' = stdout)."),
    time_unit: str = TIME_UNIT_OPT,
    quiet: bool = QUIET_OPT,
):
    """Which chamber programme separates a thermal lag from the channel gradient (and both
    from the Shupe term)?

    Scores cycles between --low and --high (ramp rates up to --max-rate, soaks 15-120 min)
    and the baseline by the noncentrality of each true effect against its rival under the
    noise model, and prints the best with the loop duel's predicted power (docs/plan.md).

    Examples:
      fogbayes plan-chamber --noise 0.005,0.02,0.02 --hours 3 --fs 10
      fogbayes plan-chamber chamber_run.csv --max-rate 3 --lag-tau 1200,1800 --json plan.json
    """
    from ..errors import ArgumentError
    from ..effects.temperature_rate import TemperatureRate
    from ..effects.thermal_lag import ThermalLag
    from ..plan.programme import noise_for_plan, pairs_for, plan_programme

    refuse_overwrite({"the pilot recording": pilot}, {"--json": json_out})
    if (pilot is None) == (noise is None):
        raise ArgumentError("give either a pilot recording or --noise N,B,K",
                            column="--noise" if pilot is None else "PILOT",
                            fix="e.g. fogbayes plan-chamber --noise 0.005,0.02,0.02")
    lag_s = _floats(lags, "--lags", 2)
    taus = _floats(lag_tau, "--lag-tau")
    for flag, v in (("--hours", hours), ("--fs", fs), ("--max-rate", max_rate),
                    ("--lag-coeff", lag_coeff), ("--rate-coeff", rate_coeff)):
        if not v > 0:
            raise ArgumentError(f"{flag} must be positive (got {v:g})", column=flag,
                                fix=f"give a positive {flag}")
    if not (low <= room <= high and low < high):
        raise ArgumentError(f"need --low <= --room <= --high (got {low:g}, {room:g}, {high:g})",
                            column="--low/--room/--high", fix="e.g. --low -20 --room 20 --high 60")
    if min(lag_s) <= 0 or lag_s[0] >= lag_s[1] or min(taus) <= 0:
        raise ArgumentError("--lags must be two increasing positive time constants and "
                            "--lag-tau positive", column="--lags/--lag-tau",
                            fix="e.g. --lags 300,900 --lag-tau 1800")
    baseline = None if programme is None else _segments_file(programme)
    with progress("Fitting the noise model and scoring programmes"):
        if pilot is not None:
            rec = load_recording(pilot, time_unit=time_unit)
            nz, dur, rate = noise_for_plan(rec, lags=lag_s, room=room)
            source = str(pilot)
        else:
            n_b_k = _floats(noise, "--noise", 3)
            nz, dur, rate = noise_for_plan(allan=dict(zip("NBK", n_b_k)), duration=hours * 3600,
                                           fs=fs, lags=lag_s, room=room)
            source = f"Allan terms N {n_b_k[0]:g}, B {n_b_k[1]:g}, K {n_b_k[2]:g}"
        pairs = pairs_for({ThermalLag.name: (lag_coeff, taus),
                           TemperatureRate.name: (rate_coeff, [None])})
        try:
            plan = plan_programme(nz, pairs, duration=dur, fs=rate, lags=lag_s, low=low,
                                  high=high, room=room, max_rate=max_rate, baseline=baseline)
        except ValueError as exc:
            raise ArgumentError(str(exc), column="--max-rate/--hours",
                                fix="allow faster ramps or plan a longer record") from None
    doc = plan.to_json()
    doc["settings"]["noise_from"] = source
    lines = _lines(doc)
    if json_out is None:
        sys.stdout.write("\n".join(lines) + "\n")
        return
    write_json(doc, json_out)
    for line in lines:
        say(line)
