"""Never clobber, never half-write: every command that writes files.

* An output path that is an input of the same command (the recording, the fit document,
  through a symbolic or hard link, or a folder output holding an input), or two outputs
  naming one file, is refused before any work: exit 2, one ``fogbayes: error:`` line, the
  input byte-identical and nothing written.
* Outputs are atomic (:mod:`fogbayes.data.atomic`): a command killed by SIGTERM or Ctrl-C
  while it writes leaves the old file (or none) under the final name and no temporary
  file. The kill tests run ``python -m fogbayes`` as a subprocess; all but one slow down
  the rename of one chosen output (a sleep after its fsync) so that the signal is sure to
  land inside the writing window; the other one is not patched at all.
* ``fogbayes batch``: summary.json is written last; a re-run removes the stale outputs of
  recordings it did not write this time.

Small simulated recordings (20 min at 1 Hz); the whole module runs in ~30 s on 2 cores.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from fogbayes.cli import main
from fogbayes.data import load, save
from fogbayes.data.atomic import atomic_path, is_temp_name, write_text
from fogbayes.errors import FileFormatError
from fogbayes.simulate import simulate

N = 1200  # samples of the test recordings (1200 s at 1 Hz)


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """A recording (CSV and NPZ) and its bias-t fit document, made once."""
    d = tmp_path_factory.mktemp("safe")
    rec = simulate("thermal", seed=1, duration=float(N), fs=1.0).recording
    csv = save(rec, d / "rec.csv")
    save(rec, d / "rec.npz")  # read by the --stream refusal case
    fit = d / "fit.json"
    assert main(["-q", "fit", str(csv), "-m", "bias-t", "--json", str(fit)]) == 0
    # a tiny allan document: a report from it needs no fit (fast in a subprocess)
    tau = [1.0, 2.0, 4.0, 8.0]
    adev = [0.3, 0.22, 0.16, 0.12]
    (d / "allan.json").write_text(json.dumps({
        "model": "allan", "converged": True, "tau": tau, "adev": adev,
        "adev_low": [a * 0.9 for a in adev], "adev_high": [a * 1.1 for a in adev],
        "fit": {"method": "wls", "terms": {}}}))
    return d


def _temps(folder: Path) -> list[str]:
    return sorted(p.name for p in Path(folder).rglob("*") if is_temp_name(p.name))


# ------------------------------------------------------------------------------ refusals
def _refusals(d: Path, t: Path) -> list:
    rec, fit, npz = d / "rec.csv", d / "fit.json", d / "rec.npz"
    return [
        # (argv, the path the message must name, paths that must not appear)
        (["compensate", rec, "-p", fit, "-o", rec], rec, []),
        (["compensate", rec, "-p", fit, "-o", t / "c.csv", "--json", fit], fit, [t / "c.csv"]),
        (["compensate", rec, "-p", fit, "-o", t / "c.csv", "--json", rec], rec, [t / "c.csv"]),
        (["compensate", rec, "-p", fit, "-o", t / "link.csv"], t / "link.csv", []),
        (["compensate", rec, "-p", fit, "-o", t / "hard.csv"], t / "hard.csv", []),
        (["compensate", npz, "-p", fit, "-o", d, "--stream"], d, []),  # folder holding REC
        (["fit", rec, "-m", "bias-t", "--json", rec], rec, []),
        (["report", rec, "--fit", fit, "--out", rec], rec, []),
        (["report", rec, "--fit", fit, "--out", fit], fit, []),
        (["loop", rec, "-m", "bias-t", "--json", t / "l.json", "--compensated", rec], rec,
         [t / "l.json"]),
        (["loop", rec, "-m", "bias-t", "--json", rec, "--compensated", t / "l.csv"], rec,
         [t / "l.csv"]),
        (["loop", rec, "-m", "bias-t", "--json", t / "l.json", "--compensated", t / "l.csv",
          "--report", rec], rec, [t / "l.json", t / "l.csv"]),
        (["allan", rec, "--json", t / "a.json", "--plot", rec], rec, [t / "a.json"]),
        (["info", rec, "--json", rec], rec, []),
        (["simulate", "thermal", "-o", t / "s.csv", "--truth", t / "s.csv"], t / "s.csv",
         [t / "s.csv"]),
        (["demo", "--out", t / "demo", "--json", t / "demo" / "report.html"],
         t / "demo" / "report.html", [t / "demo"]),
        (["batch", d, "-m", "bias-t", "--out", t / "b", "--json", rec, "--pattern", "rec.csv"],
         rec, [t / "b"]),
    ]


@pytest.mark.parametrize("case", range(17))
def test_an_output_that_is_an_input_is_refused(files, tmp_path, capsys, case):
    (tmp_path / "link.csv").symlink_to(files / "rec.csv")
    os.link(files / "rec.csv", tmp_path / "hard.csv")
    argv, named, absent = _refusals(files, tmp_path)[case]
    before = {p: p.read_bytes() for p in files.iterdir() if p.is_file()}
    code = main(["-q", *map(str, argv)])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1, err
    assert err[0].startswith("fogbayes: error: ") and str(named) in err[0], err[0]
    assert "Fix:" in err[0] and ("would destroy the input" in err[0]
                                 or "name the same file" in err[0])
    assert {p: p.read_bytes() for p in files.iterdir() if p.is_file()} == before
    assert not any(p.exists() for p in absent)
    assert _temps(files) == [] and _temps(tmp_path) == []


def test_refusal_cases_cover_every_listed_case(files, tmp_path):
    assert len(_refusals(files, tmp_path)) == 17  # keep the parametrisation in step


# ------------------------------------------------------------------------- atomic writer
def test_atomic_path_keeps_the_old_file_on_any_exception(tmp_path):
    target = tmp_path / "out.json"
    target.write_text("old\n")
    target.chmod(0o640)
    for exc in (RuntimeError("boom"), KeyboardInterrupt(), SystemExit(143)):
        with pytest.raises(type(exc)), atomic_path(target) as tmp:
            tmp.write_text("half")
            assert tmp.parent == tmp_path and is_temp_name(tmp.name) and tmp.suffix == ".json"
            raise exc
        assert target.read_text() == "old\n" and _temps(tmp_path) == []
    write_text(target, "new\n")
    assert target.read_text() == "new\n" and (target.stat().st_mode & 0o777) == 0o640
    assert _temps(tmp_path) == []
    with pytest.raises(FileFormatError, match="is a folder"), atomic_path(tmp_path):
        pass


def test_stream_folder_output_is_replaced_whole_and_never_merged(files, tmp_path):
    from fogbayes.stream import compensate_stream

    fit = json.loads((files / "fit.json").read_text())
    out = tmp_path / "odir"
    first = compensate_stream(files / "rec.npz", fit, out, rows=1024)
    assert sorted(p.name for p in out.iterdir()) == ["outlier.npy", "output.npy", "time.npy"]
    (out / "stale.npy").write_bytes(b"x")  # an earlier output's extra column: replaced
    compensate_stream(files / "rec.npz", fit, out, rows=1024)
    assert sorted(p.name for p in out.iterdir()) == ["outlier.npy", "output.npy", "time.npy"]
    assert np.load(out / "output.npy").size == first.n == N
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "notes.txt").write_text("keep me")
    with pytest.raises(FileFormatError, match="holds other files"):
        compensate_stream(files / "rec.npz", fit, mine, rows=1024)
    assert [p.name for p in mine.iterdir()] == ["notes.txt"] and _temps(tmp_path) == []


def test_batch_rerun_removes_stale_outputs_and_writes_the_summary_last(files, tmp_path,
                                                                        capsys):
    fleet, out = tmp_path / "fleet", tmp_path / "out"
    fleet.mkdir()
    out.mkdir()
    (fleet / "g0.csv").write_bytes((files / "rec.csv").read_bytes())
    (fleet / "bad.csv").write_text("time,output,temperature\n0,1,20\n1,abc,20\n")
    # an earlier run: bad.csv was good then; g0 was compensated with an older fit
    for name in ("bad.fit.json", "g0.compensated.csv", "summary.json", "zz.fit.json",
                 "notes.txt"):
        (out / name).write_text("earlier run\n")
    code = main(["-q", "batch", str(fleet), "-m", "bias-t", "--out", str(out)])
    capsys.readouterr()
    assert code == 1
    summary = json.loads((out / "summary.json").read_text())
    rows = {Path(r["file"]).name: r for r in summary["rows"]}
    assert rows["bad.csv"]["status"] == "error" and rows["g0.csv"]["status"] == "ok"
    assert rows["bad.csv"]["removed_stale"] == ["bad.fit.json"]
    assert rows["g0.csv"]["removed_stale"] == ["g0.compensated.csv"]
    # what is left: this run's outputs, and files of no recording of this run
    assert sorted(p.name for p in out.iterdir()) == ["g0.fit.json", "notes.txt",
                                                     "summary.json", "zz.fit.json"]
    assert json.loads((out / "g0.fit.json").read_text())["model"] == "bias-t"


# --------------------------------------------------------------------------- kill tests
#: ``python -m fogbayes`` with the fsync of the one output whose temporary name contains
#: argv[1] slowed by argv[2] seconds: the signal then lands inside that output's window.
_RUNNER = r"""
import runpy, signal, sys, time
import fogbayes.data.atomic as atomic
mark, pause = sys.argv.pop(1), float(sys.argv.pop(1))
_fsync = atomic._fsync
def slow(path):  # a write that takes `pause` s; it ends early once a stop is requested
    _fsync(path)
    if mark in str(path):
        end = time.monotonic() + pause
        while time.monotonic() < end and atomic.stop_requested() is None:
            time.sleep(0.02)
atomic._fsync = slow
signal.signal(signal.SIGINT, signal.default_int_handler)  # even if the parent ignores it
signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT, signal.SIGTERM})
# The SIGTERM handler's exception can be dropped (a finaliser) or its handler run late
# (seen in 2-core CI: the process slept on, or a killed batch wrote its summary, then
# exited 143); atomic_path checks the stop flag and the signal pipe before renaming.
sys.argv[0] = "fogbayes"
runpy.run_module("fogbayes", run_name="__main__", alter_sys=True)
"""


def _signal_state(pid: int) -> str:
    """The Sig* lines of /proc/PID/status (pending, blocked, ignored, caught), to diagnose."""
    try:
        with open(f"/proc/{pid}/status") as fh:
            return "; ".join(ln.strip() for ln in fh if ln.startswith(("Sig", "Shd")))
    except OSError:
        return "no /proc status"


def _kill_while_writing(args, watch: Path, mark: str | None, sig=signal.SIGTERM,
                        timeout: float = 60.0):
    """Start the command, signal it once a temporary file whose name holds ``mark``
    appears under ``watch`` (and is still there 50 ms later: the slow writer's own);
    returns (exit code, stderr, whether it was signalled)."""
    if mark is None:
        cmd = [sys.executable, "-m", "fogbayes", *map(str, args)]
    else:
        cmd = [sys.executable, "-c", _RUNNER, mark, "60", *map(str, args)]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    signalled, deadline = False, time.monotonic() + timeout
    try:
        while time.monotonic() < deadline and proc.poll() is None:
            seen = [p for p in watch.iterdir()
                    if is_temp_name(p.name) and (mark is None or mark in p.name)]
            # the slow write holds its temporary; the CLI's check that an output can be
            # written makes one with the same name and removes it at once (a signal sent
            # then lands before the work started: a rare false failure, seen 1 in 4 suites)
            if seen and mark is not None:
                time.sleep(0.05)
                seen = [p for p in seen if p.exists()]
            if seen:
                proc.send_signal(sig)
                signalled = True
                break
            time.sleep(0.005)
        try:
            _, err = proc.communicate(timeout=timeout)
        except subprocess.TimeoutExpired:
            raise AssertionError(f"no exit {timeout} s after the signal; {_signal_state(proc.pid)}")
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert signalled or proc.returncode == 0, err  # finished first: it must have succeeded
    return proc.returncode, err, signalled


def _old(path: Path) -> bytes:
    text = f"old content of {path.name}\n".encode()
    path.write_bytes(text)
    return text


def test_simulate_killed_while_writing_leaves_the_old_file_unpatched(tmp_path):
    # the real command, nothing slowed: 360 000 rows take ~1 s to write
    out = tmp_path / "big.csv"
    old = _old(out)
    code, err, signalled = _kill_while_writing(
        ["-q", "simulate", "thermal", "--duration", "36000", "--fs", "10", "-o", out],
        tmp_path, None)
    assert signalled, "no temporary file seen: the output was not written atomically"
    assert code in (0, 143), err  # 0: the signal came after the rename
    if code == 143:
        assert "terminated" in err
    # the old file, or (the signal came after the rename) the complete new one: never a part
    assert out.read_bytes() == old or load(out).n == 360_000
    assert _temps(tmp_path) == []


def test_a_temporary_whose_writer_was_never_resumed_is_removed_as_the_command_ends(tmp_path):
    """SIGTERM's exception can land in contextlib's own ``__exit__`` frame, before the
    writer's generator is resumed to remove its temporary (seen once in 2-core CI: a
    ``.r.tmp-*.html`` left by ``report``): the command removes what is still pending."""
    from fogbayes.cli import main
    from fogbayes.data.atomic import atomic_path

    writer = atomic_path(tmp_path / "x.csv")
    writer.__enter__().write_text("partial\n")  # then never exited
    assert _temps(tmp_path) != []
    assert main(["--quiet", "info", str(tmp_path / "missing.csv")]) == 2
    assert _temps(tmp_path) == [] and not (tmp_path / "x.csv").exists()


def test_compensate_ctrl_c_while_writing_the_json_keeps_the_old_one(files, tmp_path):
    comp, summ = tmp_path / "c.csv", tmp_path / "s.json"
    old_comp = _old(comp)
    old = _old(summ)
    code, err, _ = _kill_while_writing(
        ["-q", "compensate", files / "rec.csv", "-p", files / "fit.json", "-o", comp,
         "--json", summ], tmp_path, ".s.tmp-", sig=signal.SIGINT)
    assert code in (130, 1), err  # Ctrl-C: typer's 130 (click alone: 1, "Aborted!")
    assert summ.read_bytes() == old
    # written before, but the outputs appear all or none (fogbayes.data.atomic.all_or_none)
    assert comp.read_bytes() == old_comp
    assert _temps(tmp_path) == []


def test_fit_killed_while_writing_leaves_no_file(files, tmp_path):
    out = tmp_path / "f.json"
    code, err, _ = _kill_while_writing(
        ["-q", "fit", files / "rec.csv", "-m", "bias-t", "--json", out], tmp_path, ".f.tmp-")
    assert code == 143 and "terminated" in err
    assert not out.exists() and _temps(tmp_path) == []


def test_report_killed_while_writing_leaves_the_old_report(files, tmp_path):
    out = tmp_path / "r.html"
    old = _old(out)
    code, _, _ = _kill_while_writing(
        ["-q", "report", files / "rec.csv", "--fit", files / "allan.json", "-o", out],
        tmp_path, ".r.tmp-")
    assert code == 143 and out.read_bytes() == old and _temps(tmp_path) == []


def test_stream_folder_killed_while_writing_leaves_the_old_folder(files, tmp_path):
    out = tmp_path / "odir"
    out.mkdir()
    old = _old(out / "output.npy")
    code, _, _ = _kill_while_writing(
        ["-q", "compensate", files / "rec.npz", "-p", files / "fit.json", "-o", out,
         "--stream", "--chunk-rows", "1024"], tmp_path, ".odir.tmp-")
    assert code == 143
    assert [p.name for p in out.iterdir()] == ["output.npy"]
    assert (out / "output.npy").read_bytes() == old and _temps(tmp_path) == []


def test_batch_killed_mid_run_leaves_no_summary_and_the_old_outputs(files, tmp_path):
    fleet, out = tmp_path / "fleet", tmp_path / "out"
    fleet.mkdir()
    out.mkdir()
    for name in ("g0.csv", "g1.csv"):
        (fleet / name).write_bytes((files / "rec.csv").read_bytes())
    _old(out / "summary.json")
    old = _old(out / "g1.fit.json")
    code, _, _ = _kill_while_writing(
        ["-q", "batch", fleet, "-m", "bias-t", "--out", out], out, ".g1.fit.tmp-")
    assert code == 143
    assert not (out / "summary.json").exists()  # the earlier run's: removed at the start
    assert (out / "g1.fit.json").read_bytes() == old  # killed while replacing it
    assert json.loads((out / "g0.fit.json").read_text())["model"] == "bias-t"  # complete
    assert _temps(tmp_path) == []


@pytest.mark.parametrize("command", ["fit", "compensate", "batch"])
def test_an_output_under_a_regular_file_is_one_line(command, tmp_path, capsys):
    """An output path whose folder is a regular file: exit 2 and one line, no traceback."""
    rec = save(simulate("thermal", seed=2, duration=600.0, fs=1.0).recording,
               tmp_path / "runs" / "r.csv")
    blocker = tmp_path / "afile"
    blocker.write_text("not a folder\n")
    fit = tmp_path / "f.json"
    assert main(["-q", "fit", str(rec), "-m", "bias-t", "--json", str(fit)]) == 0
    args = {"fit": ["fit", str(rec), "-m", "bias-t", "--json", str(blocker / "x.json")],
            "compensate": ["compensate", str(rec), "-p", str(fit), "-o", str(blocker / "c.csv")],
            "batch": ["batch", str(rec.parent), "-m", "bias-t", "--out", str(blocker / "out")]}
    capsys.readouterr()
    assert main(["-q", *args[command]]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("fogbayes: error:") and "afile" in err[0], err
    assert blocker.read_text() == "not a folder\n"


def test_a_requested_stop_abandons_the_write_before_the_rename(tmp_path):
    """The SIGTERM handler's flag alone (its exception dropped in a finaliser) still keeps
    a file that was being written from replacing the old one."""
    from fogbayes.data.atomic import Stopped, atomic_path, clear_stop, request_stop

    target = tmp_path / "doc.json"
    old = _old(target)
    try:
        with pytest.raises(Stopped) as info:
            with atomic_path(target) as tmp:
                tmp.write_text("new, complete as far as this writer knows\n")
                request_stop(143)
        assert info.value.code == 143
    finally:
        clear_stop()
    assert target.read_bytes() == old and _temps(tmp_path) == []


def test_a_signal_whose_handler_has_not_run_still_abandons_the_write(tmp_path):
    """The signal pipe alone (the Python handler run late, or never setting the flag: a
    no-op one here) keeps a file being written from replacing the old one."""
    from fogbayes.data.atomic import Stopped, atomic_path, clear_stop, watch_signals

    target = tmp_path / "doc.json"
    old = _old(target)
    previous = signal.signal(signal.SIGTERM, lambda signum, frame: None)
    unwatch = watch_signals()
    try:
        with pytest.raises(Stopped) as info:
            with atomic_path(target) as tmp:
                tmp.write_text("new, complete as far as this writer knows\n")
                os.kill(os.getpid(), signal.SIGTERM)
        assert info.value.code == 143
    finally:
        unwatch()
        clear_stop()
        signal.signal(signal.SIGTERM, previous)
    assert target.read_bytes() == old and _temps(tmp_path) == []
