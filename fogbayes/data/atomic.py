"""Write outputs so that a reader finds the old file or the new one, never half of one.

:func:`atomic_path` / :func:`write_text`: written to a hidden ``.<stem>.tmp-<pid>-<random><suffix>``
in the same folder, ``fsync``-ed, then :func:`os.replace`-d over the final name; any failure before
(exception, Ctrl-C, SIGTERM) removes the temporary file. :func:`all_or_none` holds several outputs'
renames until the last is written. :func:`atomic_dir` does the same for a folder of ``.npy`` files;
an existing target is replaced only if it holds nothing else (:func:`check_replaceable_dir`).
"""

from __future__ import annotations

import os
import re
import secrets
import shutil
import signal
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

from ..errors import FileFormatError

#: Marks the temporary files and folders of an unfinished write (``.<stem>.tmp-...``).
TMP_MARK = ".tmp-"


class Stopped(SystemExit):
    """A stop was requested (SIGTERM) while a file was being written: it is not renamed."""


#: Exit code of a stop requested by a signal handler (:func:`request_stop`), else None.
_STOP: dict = {"code": None}
#: Read end of the pipe the C-level signal handler writes each signal's number to
#: (:func:`watch_signals`), else None.
_WAKE: dict = {"read": None}


def request_stop(code: int) -> None:
    """Ask every atomic write still running to abandon its file instead of renaming it.

    A signal handler raises its exception where the main thread happens to be; inside a
    finaliser or a weakref callback Python prints and drops it, and the command would go
    on. This flag is the second line: :func:`atomic_path` checks it before the rename.
    """
    _STOP["code"] = code


def clear_stop() -> None:
    _STOP["code"] = None


def watch_signals() -> Callable[[], None]:
    """Have the interpreter's C-level handler note every signal in a pipe that
    :func:`stop_requested` reads; returns the function that undoes it. Main thread only.

    The third line, for a Python handler that has not run yet: CPython 3.11 runs it only
    when the main thread next checks its eval breaker, and a thread of a C library that
    takes the GIL can clear that breaker, so the handler can wait until the work is done
    (seen in CI: a batch killed while writing wrote its summary, then exited 143). The C
    handler writes the pipe at once, in whatever thread the signal landed.
    """
    read, write = os.pipe()
    os.set_blocking(read, False)
    os.set_blocking(write, False)
    previous = signal.set_wakeup_fd(write, warn_on_full_buffer=False)
    _WAKE["read"] = read

    def undo() -> None:
        signal.set_wakeup_fd(previous)
        _WAKE["read"] = None
        os.close(read)
        os.close(write)

    return undo


def stop_requested() -> int | None:
    """The exit code of a stop requested by SIGTERM (143) or SIGINT (130), else None: the
    flag of :func:`request_stop`, or a signal noted in the pipe of :func:`watch_signals`
    whose Python handler has not run yet."""
    if _STOP["code"] is None and _WAKE["read"] is not None:
        try:
            noted = os.read(_WAKE["read"], 4096)
        except (BlockingIOError, OSError):
            noted = b""
        for signum in noted:
            if signum in (signal.SIGTERM, signal.SIGINT):
                request_stop(128 + signum)
                break
    return _STOP["code"]


def temp_path(path: str | Path) -> Path:
    """A fresh hidden temporary name beside ``path``, keeping its suffix."""
    path = Path(path)
    return path.with_name(f".{path.stem}{TMP_MARK}{os.getpid()}-{secrets.token_hex(4)}"
                          f"{path.suffix}")


def new_temp(path: str | Path) -> Path:
    """:func:`temp_path`, registered for :func:`remove_orphans` until it is renamed into
    place or removed (a name renamed away by other means is a no-op there)."""
    tmp = temp_path(path)
    _LIVE.add(tmp)
    return tmp


def final_path(path: str | Path) -> Path:
    """The path a temporary name of :func:`temp_path` stands for (``.c.tmp-12-ab.csv`` ->
    ``c.csv``, in the same folder); any other path unchanged. For messages: the user named
    the final path, never the temporary one."""
    path = Path(path)
    m = re.fullmatch(rf"\.(.*){re.escape(TMP_MARK)}\d+-[0-9a-f]+(\.[^.]*)?", path.name)
    return path if m is None else path.with_name(m.group(1) + (m.group(2) or ""))


def is_temp_name(name: str) -> bool:
    """Whether ``name`` is a temporary file or folder of :func:`atomic_path`/:func:`atomic_dir`."""
    return name.startswith(".") and TMP_MARK in name


def _fsync(path: Path) -> None:
    """Flush ``path``'s data to disk before it is renamed into place."""
    fd = os.open(path, os.O_RDWR)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def _fsync_dir(folder: Path) -> None:
    """Make the rename itself durable (POSIX; a no-op where folders cannot be opened)."""
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


#: Temporaries of :func:`new_temp` not yet renamed into place nor removed.
_LIVE: set = set()


def remove_orphans() -> None:
    """Remove every temporary of :func:`new_temp` still pending (files and folders; never a
    replaced folder set aside). The CLI calls it as a command ends: a signal can land in a
    context manager's own frames, before the writer is resumed to clean up, and would leave
    its temporary behind."""
    for tmp in list(_LIVE):
        _remove(tmp)


def _remove(path: Path) -> None:
    try:
        if path.is_dir() and not path.is_symlink():
            shutil.rmtree(path, ignore_errors=True)
        else:
            path.unlink()
    except FileNotFoundError:
        pass
    except OSError:
        pass  # best effort: the final name is untouched either way
    _LIVE.discard(path)


@contextmanager
def atomic_path(path: str | Path) -> Iterator[Path]:
    """Yield a temporary path to write ``path``'s content to; rename it into place on success.

    The parent folder is created. On any exception (``KeyboardInterrupt`` and ``SystemExit``
    included) the temporary file is removed and ``path`` is left as it was. An existing
    ``path`` that is not a regular file (``/dev/null``, a named pipe) is written directly.

    Example:
        >>> with atomic_path("out.png") as tmp:          # doctest: +SKIP
        ...     fig.savefig(tmp)
    """
    path = Path(path)
    if path.is_dir():
        raise FileFormatError("is a folder, not a file", file=str(path),
                              fix="name a file inside it, or another path")
    if path.exists() and not path.is_file():
        yield path  # a device or a pipe: nothing to replace, nothing to protect
        return
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise unwritable(path, exc) from None
    tmp = new_temp(path)
    try:
        yield tmp
        if not tmp.is_file():
            raise FileFormatError("the writer left no file", file=str(path))
        _fsync(tmp)
        if stop_requested() is not None:  # stopped while writing: never rename a doubtful file
            raise Stopped(_STOP["code"])
        if _BATCH["files"] is not None:  # inside all_or_none(): renamed when it ends
            _BATCH["files"].append((tmp, path))
            return
        _rename(tmp, path)
    except OSError as exc:
        _remove(tmp)
        if _names(exc, tmp):  # the user named ``path``, never the hidden temporary
            raise unwritable(path, exc) from None
        raise
    except BaseException:
        _remove(tmp)
        raise
    _fsync_dir(path.parent)


def _rename(tmp: Path, path: Path) -> None:
    if path.is_file():  # keep the permissions of the file replaced
        shutil.copymode(path, tmp)
    os.replace(tmp, path)
    _LIVE.discard(tmp)


#: The files written inside :func:`all_or_none`, (temporary, final) in order; None outside.
_BATCH: dict = {"files": None}


@contextmanager
def all_or_none() -> Iterator[None]:
    """Hold back the renames of every :func:`atomic_path` write inside the block until it
    ends: then all are renamed into place; on an exception (Ctrl-C and SIGTERM included)
    none is, and their temporary files are removed -- a command's outputs appear all or
    none. Inside the block a file written is not yet under its final name: not for code
    that reads back what it wrote. Nested blocks join the outermost one.
    """
    if _BATCH["files"] is not None:
        yield
        return
    _BATCH["files"] = files = []
    renamed = 0  # the temporaries before this one are in place; the rest are removed on failure
    try:
        yield
        if stop_requested() is not None:
            raise Stopped(_STOP["code"])
        _BATCH["files"] = None
        for tmp, path in files:
            try:
                _rename(tmp, path)
            except OSError as exc:
                raise unwritable(path, exc) from None
            renamed += 1
        for folder in {path.parent for _, path in files}:
            _fsync_dir(folder)
    except BaseException:  # a signal between two renames included
        for tmp, _ in files[renamed:]:
            _remove(tmp)
        raise
    finally:
        _BATCH["files"] = None


def pending(path: str | Path) -> Path:
    """The file that holds ``path``'s new content now: inside :func:`all_or_none`, the
    temporary one written for it and not yet renamed (for a step that reads it back, as
    the PDF printer reads the HTML); else ``path`` itself."""
    path = Path(path)
    for tmp, final in reversed(_BATCH["files"] or []):
        if final == path or final.resolve() == path.resolve():
            return tmp
    return path


def _names(exc: OSError, tmp: Path) -> bool:
    """Whether ``exc`` is about the temporary ``tmp`` (its file name, or its name in the
    message of a writer that does not set ``filename``)."""
    return any(str(f) == str(tmp) for f in (exc.filename, exc.filename2) if f) or \
        tmp.name in str(exc)


def check_writable(path: str | Path, *, folder: bool = False) -> None:
    """Raise the one-line error :func:`atomic_path` (or, ``folder``, :func:`atomic_dir`)
    would raise for ``path`` only after the work: ``path`` an existing folder where a file is
    written, a file where a folder should be, or a folder that cannot be written to.

    Checked by doing what the writer does first: a hidden temporary file is created (and
    removed at once) in the nearest existing folder on the way to ``path`` -- permission
    bits alone do not tell (root, read-only file systems, ACLs). Creates nothing that stays.
    """
    path = Path(path)
    if path.is_dir() and not folder:
        raise FileFormatError("is a folder, not a file", file=str(path),
                              fix="name a file inside it, or another path")
    if path.exists() and not path.is_file() and not path.is_dir():
        return  # a device or a pipe: written directly
    where = path.parent
    while not where.exists() and where != where.parent:
        where = where.parent
    if not where.is_dir():
        raise unwritable(path, NotADirectoryError(20, "Not a directory"))
    probe = new_temp(where / path.name)
    try:
        fd = os.open(probe, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o600)
    except OSError as exc:
        raise unwritable(path, exc) from None
    os.close(fd)
    _remove(probe)


def unwritable(path: Path, exc: OSError) -> FileFormatError:
    """The one-line error for an output path that cannot be written (under a regular file,
    a read-only folder, ...)."""
    blocker = next((p for p in path.parents if p.is_file()), None)
    why = (f"'{blocker}' is a file, not a folder" if blocker is not None
           else f"cannot write here ({exc.strerror or exc})")
    return FileFormatError(why, file=str(path), fix="choose a path in a folder you can write to")


@contextmanager
def atomic_open(path: str | Path, mode: str = "w", **kwargs):
    """``open(path, mode)`` on a temporary file that replaces ``path`` when closed cleanly."""
    with atomic_path(path) as tmp, open(tmp, mode, **kwargs) as fh:
        yield fh


def write_text(path: str | Path, text: str, encoding: str = "utf-8") -> Path:
    """Write ``text`` to ``path`` atomically; returns ``path``."""
    path = Path(path)
    with atomic_open(path, "w", encoding=encoding, newline="\n") as fh:
        fh.write(text)
    return path


def check_replaceable_dir(path: str | Path) -> None:
    """Refuse a folder output whose target exists and holds more than ``.npy`` files.

    Such a folder is not an earlier output of fogbayes; replacing it would delete the other
    files, and writing into it would mix two runs' columns. Raised before any work.
    """
    path = Path(path)
    if not path.exists():
        return
    if not path.is_dir():
        raise FileFormatError("exists and is a file, not a folder", file=str(path),
                              fix="remove it, or name a folder (or a .npz/.parquet file)")
    other = sorted(p.name for p in path.iterdir()
                   if not (p.is_file() and p.suffix == ".npy"))
    if other:
        shown = ", ".join(other[:3]) + (", ..." if len(other) > 3 else "")
        raise FileFormatError(f"the output folder holds other files ({shown}); it is replaced "
                              "as a whole", file=str(path),
                              fix="name a new or empty folder, or one holding only an earlier "
                                  "output's .npy files")


@contextmanager
def atomic_dir(path: str | Path) -> Iterator[Path]:
    """Yield a temporary folder to fill; it replaces the folder ``path`` on success.

    ``path`` must not exist, or be a folder :func:`check_replaceable_dir` accepts. The old
    folder is renamed aside, the new one renamed into place, and the old one deleted: at
    every moment the final name holds the complete old folder, the complete new one, or
    nothing (for the instant between the two renames; an exception there puts the old one
    back). On any exception the temporary folder is removed.
    """
    path = Path(path)
    check_replaceable_dir(path)
    tmp = new_temp(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp.mkdir()
    except OSError as exc:
        raise unwritable(path, exc) from None
    old = None
    try:
        yield tmp
        for f in tmp.iterdir():
            if f.is_file():
                _fsync(f)
        _fsync_dir(tmp)
        if stop_requested() is not None:
            raise Stopped(_STOP["code"])
        check_replaceable_dir(path)  # still ours to replace?
        if path.exists():
            old = temp_path(path.with_name(path.name + ".old"))
            os.replace(path, old)
        try:
            os.replace(tmp, path)
        except BaseException:
            if old is not None and not path.exists():
                os.replace(old, path)
                old = None
            raise
    except BaseException:
        _remove(tmp)
        raise
    _fsync_dir(path.parent)
    if old is not None:
        _remove(old)
