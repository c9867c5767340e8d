"""``fogbayes pool RUNS... --json OUT``: the noise of a population of runs or units."""

from __future__ import annotations

from pathlib import Path

import typer

from ._app import app
from ._common import (QUIET_OPT, TIME_UNIT_OPT, channels, load_recording, progress,
                      reading_options, refuse_overwrite, say, write_json)

_MODELS = ("allan", "bias-t")


def recording_paths(paths: list[Path]) -> list[Path]:
    """The recordings named: files as given, folders expanded to the recordings they hold
    (.csv, .parquet, .npz and gyro logs, sorted by name; other files ignored)."""
    from ..data.io import FORMATS
    from ..data.logs import LOG_SUFFIXES
    from ..errors import FileFormatError

    out = []
    for p in paths:
        if p.is_dir():
            suffixes = (set(FORMATS) - {".txt"}) | set(LOG_SUFFIXES)  # .txt: notes, too often
            found = sorted(q for q in p.iterdir() if q.is_file() and q.suffix.lower() in suffixes)
            if not found:
                raise FileFormatError("the folder holds no recordings", file=str(p),
                                      fix="name the files, or a folder of .csv/.parquet/.npz "
                                          "files or gyro logs")
            out += found
        elif p.exists():
            out.append(p)
        else:
            raise FileFormatError("file not found", file=str(p), fix="check the path")
    seen: dict[Path, Path] = {}
    for p in out:
        if p.resolve() in seen:  # one unit counted twice would halve the spread
            raise FileFormatError(f"named twice (also as {seen[p.resolve()]})", file=str(p),
                                  fix="name each recording once")
        seen[p.resolve()] = p
    return out


def _names(recs, paths) -> list[str]:
    """Unit names: the sensor ids; where ids repeat, the file names; where those repeat too
    (``a/imu.npz``, ``b/imu.npz``), the paths below the folder they share."""
    import os

    ids = [r.meta.sensor_id for r in recs]
    if len(set(ids)) == len(ids):
        return ids
    names = [p.name for p in paths]
    if len(set(names)) == len(names):
        return names
    full = [p.resolve() for p in paths]
    common = Path(os.path.commonpath(full))
    return [str(f.relative_to(common)) for f in full]


@app.command()
def pool(
    paths: list[Path] = typer.Argument(..., help="Recordings (one per run or unit), or "
                                                 "folders of them."),
    json_out: str = typer.Option(..., "--json", help="Pool document to write ('-' = stdout)."),
    model: str = typer.Option("allan", "--model", "-m", help="What to pool: allan (the "
                              "five-term noise model) or bias-t (the bias law in T)."),
    order: int = typer.Option(2, "--order", min=1, max=4,
                              help="bias-t: order of the bias law in T."),
    t_ref: float = typer.Option(20.0, "--t-ref", help="bias-t: reference temperature (deg C) "
                                "of the pooled coefficients a_k of (T - T_ref)^k."),
    terms: str = typer.Option("N,B,K", help="Noise terms to pool (of Q, N, B, K, R)."),
    report: Path = typer.Option(None, "--report", help="Also write the HTML pool report."),
    flag_level: float = typer.Option(None, help="Flag a unit whose leave-one-out "
                                     "p-value against the population is below this "
                                     "[default: allan 0.02, bias-t 0.01]."),
    seed: int = typer.Option(0, help="Seed of the sampler."),
    prior: Path = typer.Option(None, "--prior", help="Datasheet prior (from 'fogbayes "
                               "prior'): where the typical unit's terms lie, how loosely."),
    time_unit: str = TIME_UNIT_OPT,
    quiet: bool = QUIET_OPT,
):
    """Pool the noise (or the bias law) of several runs or units of one sensor type.

    Each recording is a unit (a sensor, or one run of a sensor). Its five-term Allan fit (as 'fogbayes allan' makes it) enters a population model of log N, log B, log K: the population median with its 90 % interval, how much units differ (the between-unit spread), the range of a new unit of this type, each unit shrunk toward the population, and units outside it flagged (leave-one-out p-value below --flag-level). With several columns (--column gx,gy,gz) or axes (--axis all) each is pooled on its own.

    Examples:
      fogbayes pool runs/ --json pool.json --report pool.html
      fogbayes pool imu1.npz imu2.npz imu3.npz --column gyro_x_dps,gyro_y_dps \\
          --output-unit deg/s --json pool.json
      fogbayes pool runs/ --prior sheet.json --json pool.json
      fogbayes pool chamber_runs/ -m bias-t --order 2 --json pool.json

    With -m bias-t each unit's bias law b(T) = sum a_k (T - T_ref)^k is fitted by GLS under its noise model (as the closed loop fits it) and the coefficients are pooled: the typical unit's bias at T_ref, slope and curvature, how much units differ, a new unit's range, and outlier units.
    """
    from ..errors import ArgumentError, about_file
    from ..allan.model import TERMS
    from ..pool.allan import fit_unit, pool_allan, pool_document
    from ..pool.thermal import fit_unit as fit_thermal
    from ..pool.thermal import pool_thermal

    if model not in _MODELS:
        raise ArgumentError(f"cannot pool model '{model}'", column="--model",
                            fix=f"use one of {', '.join(_MODELS)}")
    chosen = [t.strip().upper() for t in terms.split(",") if t.strip()]
    bad = [t for t in chosen if t not in TERMS]
    if bad or not chosen or len(set(chosen)) < len(chosen):
        raise ArgumentError(f"--terms {terms!r}: " + (f"'{bad[0]}' is not a noise term" if bad
                                                      else "name each term once"),
                            column="--terms", fix="give some of Q, N, B, K, R, e.g. N,B,K")
    if flag_level is None:
        from ..pool.allan import FLAG_LEVEL as ALLAN_LEVEL
        from ..pool.thermal import FLAG_LEVEL as THERMAL_LEVEL

        flag_level = THERMAL_LEVEL if model == "bias-t" else ALLAN_LEVEL
    if not 0.0 < flag_level < 1.0:
        raise ArgumentError(f"--flag-level is {flag_level:g}; it must lie in (0, 1)",
                            column="--flag-level", fix="e.g. --flag-level 0.01")
    if model == "bias-t" and (report is not None or prior is not None or terms != "N,B,K"):
        raise ArgumentError("--report, --prior and --terms are for noise pools (-m allan)",
                            column="--model", fix="drop them with -m bias-t (the pool "
                            "document holds the thermal pool)")
    files = recording_paths(paths)
    refuse_overwrite({**{f"recording {i + 1}": p for i, p in enumerate(files)},
                      "the --prior document": prior},
                     {"--json": json_out, "--report": report})
    sheet = None
    if prior is not None:
        from ..inference.datasheet import read_prior

        sheet = read_prior(prior)
    if len(files) < 2:
        raise ArgumentError(f"a population needs at least two recordings, got {len(files)}",
                            column="PATHS", fix="name two or more runs or units")
    pools = {}
    axis, column = (reading_options()[k] for k in ("axis", "column"))
    for name, pick in channels(axis, column):
        recs, units = [], []
        for f in files:
            recs.append(load_recording(f, time_unit=time_unit, **pick))
        names = _names(recs, files)
        for f, rec, unit_name in zip(files, recs, names):
            with progress(f"{'bias law' if model == 'bias-t' else 'Allan fit'} of {unit_name}"
                          + ("" if name is None else f", {name}")), about_file(f):
                units.append(fit_thermal(rec, order=order, t_ref=t_ref, name=unit_name)
                             if model == "bias-t" else fit_unit(rec, name=unit_name))
        with progress("pooling" + ("" if name is None else f" {name}")):
            pools[name or column] = (
                pool_thermal(units, t_ref=t_ref, seed=seed, flag_level=flag_level)
                if model == "bias-t" else
                pool_allan(units, terms=chosen, seed=seed, flag_level=flag_level, prior=sheet))
    doc = pool_document(pools, model=model)
    from ..data.atomic import all_or_none

    with all_or_none():  # --json and --report appear both or neither
        write_json(doc, json_out)
        if report is not None and model != "bias-t":
            from ..render.pool import write_pool_report

            write_pool_report(doc, report)
    if model == "bias-t":
        _say_thermal(pools)
        return
    _say_allan(pools)
    if report is not None:
        say(f"wrote {report}")


def _say_allan(pools: dict) -> None:
    for name, p in pools.items():
        say(f"[{name}] {len(p['units'])} units, converged={p['converged']}")
        for t in p["terms"]:
            pop = p["population"][t]
            m = pop["median"]
            if not pop["resolved"]:  # an upper bound only (fogbayes.pool.allan.absence_chi2)
                ev = pop["evidence"]
                say(f"  {t} population < {m['upper']:.2g} {m['unit']} "
                    f"({m['level'] * 100:g} %): not resolved, the records do not exclude "
                    f"{t} = 0 in every unit (chi2 {ev['chi2_absent']:.2g} < "
                    f"{ev['threshold']:.3g})")
                continue
            f = pop["spread"]["factor"]
            say(f"  {t} population {m['value']:.4g} [{m['low']:.4g}, {m['high']:.4g}] {m['unit']}, "
                f"units differ by x{f['value']:.3g} [x{f['low']:.3g}, x{f['high']:.3g}]")
        say("  flagged: " + (", ".join(p["flagged"]) or "none"))
        for w in p["warnings"]:
            say(f"  warning: {w}")


def _say_thermal(pools: dict) -> None:
    for name, p in pools.items():
        say(f"[{name}] {len(p['units'])} units, converged={p['converged']}, "
            f"b(T) = sum a_k (T - {p['t_ref']:g})^k")
        for t in p["terms"]:
            m, s = p["population"][t]["mean"], p["population"][t]["spread_sd"]
            say(f"  {t} population {m['value']:.4g} [{m['low']:.4g}, {m['high']:.4g}] "
                f"{m['unit']}, units differ by sd {s['value']:.3g} [{s['low']:.3g}, "
                f"{s['high']:.3g}]")
        say("  flagged: " + (", ".join(p["flagged"]) or "none"))
        for w in p["warnings"]:
            say(f"  warning: {w}")
