"""Helpers shared by the subcommands: loading recordings, writing JSON, progress."""

from __future__ import annotations

import functools
import inspect
import json
import os
import sys
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import typer
from rich.console import Console

from ..support.jsonable import (
    to_jsonable,  # the one sanitiser (fogbayes/support/jsonable.py), re-exported here
)
from ..data import Recording, load
from ..errors import FogbayesError

#: Messages for people go to stderr so that `--json -` keeps stdout clean.
console = Console(stderr=True)
QUIET = {"on": False}

REC_ARG = typer.Argument(..., help="Recording file (.csv, .parquet or .npz) or gyro log: PX4 "
                                   ".ulg, ROS 1 .bag, ROS 2 bag folder/.db3/.mcap, ArduPilot "
                                   ".bin (rates in rad/s; pip install 'fogbayes\\[logs]').",
                         show_default=False)

#: Options that say how to read a recording; the same names and help on every command.
_INPUT = "Reading the recording"
COLUMN_OPT = typer.Option("output", "--column", help="Gyro output column.",
                          rich_help_panel=_INPUT)
TIME_COLUMN_OPT = typer.Option("time", "--time-column",
                               help="Time column (in --time-unit, default s).",
                               rich_help_panel=_INPUT)
TIME_UNIT_OPT = typer.Option(None, "--time-unit",
                             help="Unit of the time column: s, ms, us or ns (converted to s). "
                                  "Default: the unit its name states (time_ms, 'time [us]'), "
                                  "else s.",
                             rich_help_panel=_INPUT, show_default=False)
DELIMITER_OPT = typer.Option(None, "--delimiter",
                             help="CSV field separator: ',', ';' or tab. Default: sniffed from "
                                  "the header and first rows.",
                             rich_help_panel=_INPUT, show_default=False)
DECIMAL_OPT = typer.Option(None, "--decimal",
                           help="CSV decimal mark: '.' or ','. Default: sniffed (',' in a "
                                "';'-separated file whose numbers read 0,63).",
                           rich_help_panel=_INPUT, show_default=False)
OUTPUT_UNIT_OPT = typer.Option(None, "--output-unit",
                               help="Output unit: deg/h, deg/s, rad/s, V, mV or Hz "
                                    "(default: the file's '# unit:' line, else deg/h).",
                               rich_help_panel=_INPUT, show_default=False)
SCALE_FACTOR_OPT = typer.Option(None, "--scale-factor",
                                help="Raw units per deg/s, for V/mV/Hz outputs.",
                                rich_help_panel=_INPUT, show_default=False)
TEMPERATURE_OPT = typer.Option(None, "--temperature",
                               help="Temperature column (repeatable; first = main). Default: "
                                    "every 'temperature', 'temperature_<k>' column.",
                               rich_help_panel=_INPUT, show_default=False)
INPUT_RATE_OPT = typer.Option("input_rate", "--input-rate-column",
                              help="Reference-rate column (deg/s), used when present.",
                              rich_help_panel=_INPUT)
TEMPERATURE_SCALE_OPT = typer.Option(1.0, "--temperature-scale",
                                     help="Temperatures are read as SCALE x value + OFFSET "
                                          "deg C (raw sensor words; values outside -100 ... "
                                          "200 deg C are refused).",
                                     rich_help_panel=_INPUT)
TEMPERATURE_OFFSET_OPT = typer.Option(0.0, "--temperature-offset",
                                      help="Added after --temperature-scale (kelvin: -273.15).",
                                      rich_help_panel=_INPUT)

#: Options for gyro logs only (fogbayes/data/logs, docs/logs.md); an error for other files.
TOPIC_OPT = typer.Option(None, "--topic",
                         help="Gyro logs: PX4 sensor_gyro (default) or sensor_combined; ROS "
                              "the sensor_msgs/Imu topic (default: the only one), optionally "
                              "',TEMPERATURE_TOPIC'; ArduPilot IMU, IMU2, ...",
                         rich_help_panel=_INPUT, show_default=False)
INSTANCE_OPT = typer.Option(None, "--instance", min=0,
                            help="Gyro logs: the sensor instance (PX4 multi_id, ArduPilot IMU "
                                 "number), default 0.",
                            rich_help_panel=_INPUT, show_default=False)
AXIS_OPT = typer.Option(None, "--axis",
                        help="Gyro logs: the body axis read as the output: x (default), y or z.",
                        rich_help_panel=_INPUT, show_default=False)


def _quiet(value: bool) -> bool:
    """``--quiet`` after a subcommand: the same switch as ``fogbayes --quiet``."""
    if value:
        QUIET["on"] = True
    return value


#: ``-q/--quiet``, accepted on every subcommand as well as on the root command.
QUIET_OPT = typer.Option(False, "--quiet", "-q", callback=_quiet,
                         help="No progress bars or status lines on stderr; results only.")


#: The options that say how to read a recording, by :func:`load_recording` keyword: the
#: option, the keyword of :func:`fogbayes.data.load` it becomes, and its Python type.
#: Every command that reads a recording has them all (:func:`add_reading_options`), so a
#: fix that names one names an option of the command that printed it.
READING_OPTIONS = {
    "column": (COLUMN_OPT, "output", str), "time_column": (TIME_COLUMN_OPT, "time", str),
    "time_unit": (TIME_UNIT_OPT, "time_unit", str), "output_unit": (OUTPUT_UNIT_OPT, "unit", str),
    "scale_factor": (SCALE_FACTOR_OPT, "scale_factor", float),
    "temperature": (TEMPERATURE_OPT, "temperature", list[str]),
    "input_rate": (INPUT_RATE_OPT, "input_rate", str),
    "temperature_scale": (TEMPERATURE_SCALE_OPT, "temperature_scale", float),
    "temperature_offset": (TEMPERATURE_OFFSET_OPT, "temperature_offset", float),
    "topic": (TOPIC_OPT, "topic", str), "instance": (INSTANCE_OPT, "instance", int),
    "axis": (AXIS_OPT, "axis", str), "delimiter": (DELIMITER_OPT, "delimiter", str),
    "decimal": (DECIMAL_OPT, "decimal", str)}
#: For the running command: the reading options :func:`add_reading_options` gave it and
#: their values, and the hints :func:`load_recording` found about its time columns.
_READING: dict[str, Any] = {"added": {}, "hints": []}


def load_keywords(options: dict) -> dict:
    """:func:`fogbayes.data.load` keywords from :func:`load_recording` ones."""
    out = {READING_OPTIONS[k][1]: v for k, v in options.items()}
    if "temperature" in out:
        out["temperature"] = out["temperature"] or None  # no --temperature: the default set
    return out


def added_reading_options() -> dict:
    """The :func:`fogbayes.data.load` keywords of the reading options the running command
    was given by :func:`add_reading_options` (for a command that calls ``load`` itself)."""
    return load_keywords(_READING["added"])


def reading_options() -> dict:
    """The running command's reading options that :func:`add_reading_options` gave it, by
    parameter name (``axis``, ``column``, ``output_unit``, ...), as the user set them."""
    return dict(_READING["added"])


def _flags(param: inspect.Parameter) -> tuple:
    return tuple(getattr(param.default, "param_decls", None) or ())


def add_reading_options(app: typer.Typer) -> None:
    """Give every command that reads a recording -- one that declares ``--time-unit``
    (:data:`TIME_UNIT_OPT`) -- each of :data:`READING_OPTIONS` it does not declare itself
    (``--delimiter`` and ``--decimal`` on all of them), placed after ``--time-unit``;
    :func:`load_recording` reads their values. A :class:`FogbayesError` raised by such a
    command after a time column looked like ms or us counted as seconds gets the
    ``--time-unit`` hint first in its fix (:func:`fogbayes.data.time_units.spacing_hint`):
    a window or a rate that makes no sense in seconds mostly follows from the unit."""
    for command in app.registered_commands:
        fn = command.callback
        sig = inspect.signature(fn, eval_str=True)
        params = list(sig.parameters.values())
        at = next((k for k, p in enumerate(params) if p.default is TIME_UNIT_OPT), None)
        if at is None:
            continue
        have = {f for p in params for f in _flags(p)}
        added = [inspect.Parameter(name, params[at].kind, default=opt, annotation=kind)
                 for name, (opt, _, kind) in READING_OPTIONS.items()
                 if name not in sig.parameters and opt.param_decls[0] not in have]
        params[at + 1:at + 1] = added
        command.callback = _with_reading(fn, sig.replace(parameters=params),
                                         [p.name for p in added])


def _with_reading(fn, signature: inspect.Signature, names: list[str]):
    @functools.wraps(fn)
    def command(*args, **kwargs):
        _READING.update(added={k: kwargs.pop(k) for k in names}, hints=[])
        try:
            return fn(*args, **kwargs)
        except FogbayesError as exc:
            hints = _READING["hints"]
            if hints and hints[0] not in str(exc):
                exc.fix = f"{hints[0]}; otherwise {exc.fix}" if exc.fix else hints[0]
                exc.args = (exc._compose(),)
            raise
        finally:
            _READING.update(added={}, hints=[])

    command.__signature__ = signature
    command.__annotations__ = {p.name: p.annotation for p in signature.parameters.values()
                               if p.annotation is not inspect.Parameter.empty}
    return command


def load_recording(path: Path, *, tell: bool = True, **options) -> Recording:
    """Load a Recording as the command line says: ``options`` are :data:`READING_OPTIONS`
    keywords (``column``, ``time_column``, ``time_unit``, ``output_unit``,
    ``scale_factor``, ``temperature``, ``input_rate``, ``temperature_scale``,
    ``temperature_offset``; for a gyro log ``topic``, ``instance``, ``axis``; for CSV
    ``delimiter``, ``decimal``), those the command does not declare itself taken from the
    options :func:`add_reading_options` gave it, the rest at their defaults. What
    :func:`time_notes` finds is said on stderr (``tell``) and kept as the hint of the
    command's errors."""
    from ..errors import ArgumentError

    unknown = set(options) - set(READING_OPTIONS)
    if unknown:
        raise TypeError(f"load_recording got unknown options {sorted(unknown)}")
    options = {**_READING["added"], **options}
    try:
        rec = load(path, **load_keywords(options))
    except ArgumentError as exc:  # name the command-line flag, not fogbayes.load's keyword
        flag = "--" + (exc.column or "").lstrip("-").replace("_", "-")
        if exc.column not in ("temperature_scale", "temperature_offset", "scale_factor"):
            raise
        raise ArgumentError(exc.problem.replace(exc.column, flag), column=flag,
                            fix=(exc.fix or "").replace(exc.column, flag)) from None
    read_as, hint = time_notes(rec, path, options.get("time_unit"))
    if hint:
        _READING["hints"].append(hint)
    if tell:
        if read_as:
            say(f"{path}: time column {read_as}")
        if hint:
            say(f"warning: {path}: {hint}")
    return rec


def time_notes(rec: Recording, path: Path, time_unit: str | None) -> tuple[str | None, str | None]:
    """(how the time column was read when its name chose it, a ``--time-unit`` hint when a
    time column read in seconds by default steps like a ms or us counter); None each when
    there is nothing to say. Gyro logs carry their own time stamps: nothing."""
    from ..data.io import TIME_READ_KEY
    from ..data.logs import is_log
    from ..data.time_units import spacing_hint

    read_as = rec.meta.extra.get(TIME_READ_KEY)
    if time_unit is not None or read_as or is_log(Path(path)):
        return read_as, None
    return None, spacing_hint(rec.time)


def channels(axis: str | None, column: str) -> list[tuple[str | None, dict]]:
    """``[(name, load_recording keywords)]``: one per axis of ``--axis all`` / ``--axis x,z``
    (gyro logs) or per column of ``--column a,b,c``; ``[(None, {...})]`` for one channel."""
    from ..errors import FogbayesError

    if axis is not None and (axis == "all" or "," in axis):
        names = ["x", "y", "z"] if axis == "all" else \
            [a.strip().lower() for a in axis.split(",")]
        bad = [a for a in names if a not in ("x", "y", "z")] or \
            [a for a in set(names) if names.count(a) > 1]
        if bad:
            raise FogbayesError(f"--axis {axis!r}: {bad[0]!r} is not one of x, y, z once",
                                column="--axis", fix="use --axis all, or e.g. --axis x,z")
        return [(a, {"axis": a, "column": column}) for a in names]
    if "," in column:
        names = [c.strip() for c in column.split(",")]
        if "" in names or len(set(names)) < len(names):
            raise FogbayesError(f"--column {column!r}: empty or repeated column names",
                                column="--column", fix="name each column once, e.g. gx,gy,gz")
        return [(c, {"axis": axis, "column": c}) for c in names]
    return [(None, {"axis": axis, "column": column})]


def fit_channels(rec: Path, axis: str | None, column: str, load_kw: dict, fit,
                 what: str) -> tuple[dict, dict]:
    """Load each channel that ``--axis``/``--column`` names (:func:`channels`), fit it with
    ``fit(recording) -> document``, and return the per-channel documents and the one to
    write: the single document, or the multi-axis one (:mod:`fogbayes.data.axes_doc`)."""
    from ..errors import about_file

    docs = {}
    for name, pick in channels(axis, column):
        recording = load_recording(rec, **load_kw, **pick)
        with progress(what + ("" if name is None else f", axis {name}")), about_file(rec):
            docs[name] = fit(recording)
    if None in docs:
        return docs, docs[None]
    from ..data.axes_doc import axes_document

    return docs, axes_document(docs, source=str(rec))


def write_json(obj: Any, out: Path | str, tell: bool = True) -> None:
    """Write ``obj`` as JSON to ``out``, atomically (:mod:`fogbayes.data.atomic`); ``-``
    means stdout. ``tell``: say "wrote OUT" on stderr."""
    from ..data.atomic import write_text

    text = json.dumps(to_jsonable(obj), indent=2)
    if str(out) == "-":
        sys.stdout.write(text + "\n")
    else:
        write_text(out, text + "\n")
        if tell:
            say(f"wrote {out}")


class OverwriteError(FogbayesError):
    """An output path names an input of the same command (or another output)."""


def _paths(value) -> list[Path]:
    if value is None:
        return []
    if isinstance(value, (str, os.PathLike)):
        return [] if str(value) in ("", "-") else [Path(value)]
    return [p for v in value for p in _paths(v)]


def _keys(p: Path) -> list:
    """What identifies the file ``p``: its resolved path and, if it exists, its inode (so
    that symbolic and hard links to the same file match)."""
    keys: list = [p.resolve()]
    try:
        st = os.stat(p)
        keys.append((st.st_dev, st.st_ino))
    except OSError:
        pass
    return keys


#: The kind of file an output flag writes, whatever its path says (for suggested names).
_SUFFIX = {"--json": ".json", "--report": ".html", "--compensated": ".csv", "--pdf": ".pdf"}


def refuse_overwrite(inputs: dict[str, Any], outputs: dict[str, Any],
                     folders: tuple[str, ...] = ()) -> None:
    """Refuse an output that is an input of the same command, a folder holding one, or the
    same file as another output -- before any work, so the input is never touched -- and
    one that could not be written (:func:`check_outputs`), so that a command's outputs
    appear all or none: no output is written when another would fail after the work.

    ``inputs`` and ``outputs`` map a name for people (``"the recording"``, ``"--json"``) to a
    path, a list of paths, ``None`` or ``"-"`` (stdout: skipped). Paths are compared after
    :meth:`~pathlib.Path.resolve` and by inode (:func:`os.path.samefile`'s test) when they
    exist, so symbolic and hard links to an input count. Raises :class:`OverwriteError`
    (exit code 2). Linear in the number of paths (a batch names thousands).
    """
    check_inputs(inputs)
    seen_in: dict = {}
    holders: dict = {}  # resolved folders that hold an input -> that input
    for what, src in ((n, p) for n, v in inputs.items() for p in _paths(v)):
        for key in _keys(src):
            seen_in.setdefault(key, (what, src))
        for parent in src.resolve().parents:
            holders.setdefault(parent, (what, src))
    seen_out: dict = {}
    for flag, out in ((n, p) for n, v in outputs.items() for p in _paths(v)):
        keys = _keys(out)
        # the suggestion keeps the kind the flag writes (--json rec.csv -> rec_out.json)
        suffix = _SUFFIX.get(flag, out.suffix)
        alt = out.with_name(f"{out.stem}_out{suffix}")
        hit = next((seen_in[k] for k in keys if k in seen_in), None)
        how = "is"
        if hit is None and keys[0] in holders:
            hit, how = holders[keys[0]], "is a folder holding"
        if hit is not None:
            what, src = hit
            raise OverwriteError(f"{flag} {how} {what} ({src}), which this command reads; "
                                 "writing it would destroy the input", file=str(out),
                                 fix=f"give {flag} another path, e.g. {alt}")
        other = next((seen_out[k] for k in keys if k in seen_out), None)
        if other is not None:
            raise OverwriteError(f"{other} and {flag} name the same file; the second would "
                                 "overwrite the first", file=str(out),
                                 fix=f"give {flag} another path, e.g. {alt}")
        for key in keys:
            seen_out.setdefault(key, flag)
    check_outputs(outputs, folders)


def check_inputs(inputs: dict[str, Any]) -> None:
    """Refuse, in one line naming the file, an input that exists but cannot be read (its
    permissions), or a document (a name with "document") that is a folder. A missing file
    is left to the reader, whose message says what kind of file it wanted. The check opens
    the file, as the reader will: permission bits alone do not tell (root, ACLs)."""
    for what, src in ((n, p) for n, v in inputs.items() for p in _paths(v)):
        if not src.exists():
            continue
        if src.is_dir():
            if "document" in what:
                raise FogbayesError(f"{what} is a folder, not a file", file=str(src),
                                    fix="name the JSON file itself")
            if not os.access(src, os.R_OK | os.X_OK):
                raise FogbayesError(f"{what} cannot be read (permission denied)",
                                    file=str(src),
                                    fix=f"make it readable (chmod u+rx {src}), or name another "
                                        "folder")
            continue
        if not src.is_file():
            continue  # a pipe or a device: opening it could block; the reader will tell
        try:
            with open(src, "rb"):
                pass
        except OSError as exc:
            raise FogbayesError(f"{what} cannot be read ({exc.strerror or exc})",
                                file=str(src),
                                fix=f"make it readable (chmod u+r {src}), or name another "
                                    "file") from None


def no_typer_path_checks(app: typer.Typer) -> None:
    """Turn off typer's own readability check of ``Path`` parameters: it fails with click's
    multi-line usage box; :func:`check_inputs` says it in one ``fogbayes: error:`` line."""
    for command in app.registered_commands:
        for param in inspect.signature(command.callback).parameters.values():
            if hasattr(param.default, "readable"):
                param.default.readable = False


def check_outputs(outputs: dict[str, Any], folders: tuple[str, ...] = ()) -> None:
    """Refuse, before any work, an output path its writer would fail on after the work: an
    existing folder where a file is written (a flag in ``folders`` writes a folder), a path
    under a file, a folder that cannot be written to
    (:func:`fogbayes.data.atomic.check_writable`). One probe per folder (a batch names
    thousands of outputs in one folder). ``outputs`` as :func:`refuse_overwrite`'s."""
    from ..data.atomic import check_writable

    probed: set = set()
    for flag, out in ((n, p) for n, v in outputs.items() for p in _paths(v)):
        if out.parent in probed and not out.exists():
            continue
        try:
            check_writable(out, folder=flag in folders)
        except FogbayesError as exc:
            if flag.startswith("-"):  # name the option that takes another path
                exc.fix = (f"give {flag} a file inside it, e.g. {out / ('out' + _SUFFIX.get(flag, ''))}"
                           if exc.problem.startswith("is a folder") else
                           f"give {flag} another path, in a folder you can write to")
                exc.args = (exc._compose(),)
            raise
        probed.add(out.parent)


def say(msg: str) -> None:
    """Print a status line to stderr unless --quiet."""
    if not QUIET["on"]:
        console.print(msg, markup=False, highlight=False, soft_wrap=True)


def shows_progress() -> bool:
    """Whether progress is drawn: not with --quiet, and only on a terminal (a log file or a
    pipe reads lines; a bar drawn there leaves an empty line before the next one)."""
    return not QUIET["on"] and console.is_terminal


@contextmanager
def progress(description: str, total: int | None = None):
    """A rich progress bar on stderr; yields an ``advance`` callable.

    Silent with --quiet and when stderr is not a terminal: a bar drawn into a file or a pipe
    leaves an empty line behind, and an error must then be the one line on stderr."""
    from rich.progress import (BarColumn, Progress, SpinnerColumn, TextColumn,
                               TimeElapsedColumn)

    if not shows_progress():
        yield lambda n=1: None
        return
    cols = [SpinnerColumn(), TextColumn("{task.description}"), BarColumn(), TimeElapsedColumn()]
    with Progress(*cols, console=console, transient=True) as bar:
        task = bar.add_task(description, total=total)
        yield lambda n=1: bar.advance(task, n)
