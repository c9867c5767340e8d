"""A command's outputs appear all or none, and a failed output is named as the user wrote it.

* Every command with an output path checks each one before any work
  (:func:`fogbayes.cli._common.check_outputs`): one that cannot be written (under a file, in
  a read-only folder, an existing folder where a file goes) ends the command with exit 2,
  one ``fogbayes: error:`` line naming that path, and none of the other outputs written.
* Outputs written together (:func:`fogbayes.data.atomic.all_or_none`) are renamed into place
  only when the last is written: a failure after the first leaves none.
* A write that fails inside :func:`fogbayes.data.atomic.atomic_path` names the user's path,
  never the hidden temporary (``.c.tmp-<pid>-<hex>.csv``).

Read-only folders: a ``chmod 555`` folder, or, when the tests run as root (who writes
through permission bits), ``/sys``, where nobody can create a file.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest

from fogbayes.cli import main
from fogbayes.data import save
from fogbayes.data.atomic import is_temp_name, write_text
from fogbayes.errors import FogbayesError
from fogbayes.simulate import simulate


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """A 1200 s recording, its bias-t fit and a tiny allan document."""
    d = tmp_path_factory.mktemp("allnone")
    rec = simulate("thermal", seed=1, duration=1200.0, fs=1.0).recording
    save(rec, d / "rec.csv")
    save(rec, d / "rec2.csv")
    assert main(["-q", "fit", str(d / "rec.csv"), "-m", "bias-t", "--json",
                 str(d / "fit.json")]) == 0
    tau, adev = [1.0, 2.0, 4.0, 8.0], [0.3, 0.22, 0.16, 0.12]
    (d / "allan.json").write_text(json.dumps({
        "model": "allan", "converged": True, "tau": tau, "adev": adev,
        "adev_low": [a * 0.9 for a in adev], "adev_high": [a * 1.1 for a in adev],
        "fit": {"method": "wls", "terms": {}}}))
    return d


@pytest.fixture
def read_only(tmp_path):
    """A folder in which no file can be created, whoever runs the tests."""
    if os.geteuid() != 0:
        ro = tmp_path / "ro"
        ro.mkdir()
        ro.chmod(0o555)
        yield ro
        ro.chmod(0o755)
        return
    try:
        fd = os.open("/sys/.fogbayes-probe", os.O_CREAT | os.O_WRONLY, 0o600)
    except OSError:
        yield Path("/sys")
        return
    os.close(fd)
    os.unlink("/sys/.fogbayes-probe")
    pytest.skip("running as root and /sys is writable: no read-only folder to test with")


def _run(argv, capsys) -> tuple[int, list[str]]:
    code = main([str(a) for a in argv])
    return code, capsys.readouterr().err.splitlines()


def _cases(d: Path, t: Path, bad: Path) -> list:
    """(argv, the outputs that must not appear): every command with several outputs, its
    last output ``bad`` and the others in the writable ``t``."""
    rec, fit, adev = d / "rec.csv", d / "fit.json", d / "allan.json"
    return [
        (["loop", rec, "-m", "bias-t", "--json", t / "a.json", "--compensated", t / "c.csv",
          "--report", bad / "r.html"], [t / "a.json", t / "c.csv"]),
        (["compensate", rec, "-p", fit, "-o", t / "c.csv", "--json", bad / "s.json"],
         [t / "c.csv"]),
        (["compensate", rec, "-p", fit, "-o", bad / "c.csv", "--json", t / "s.json"],
         [t / "s.json"]),
        (["allan", rec, "--json", t / "a.json", "--plot", bad / "a.png"], [t / "a.json"]),
        (["arma", rec, "--json", t / "a.json", "--plot", bad / "a.png"], [t / "a.json"]),
        (["report", rec, "--fit", adev, "--out", t / "r.html", "--pdf", bad / "r.pdf"],
         [t / "r.html"]),
        (["simulate", "thermal", "--duration", "600", "--fs", "1", "-o", t / "s.csv",
          "--truth", bad / "truth.json"], [t / "s.csv"]),
        (["pool", rec, d / "rec2.csv", "-m", "allan", "--json", t / "p.json", "--report",
          bad / "p.html"], [t / "p.json"]),
        (["fit", rec, "-m", "bias-t", "--json", bad / "f.json"], []),
        (["demo", "--out", bad / "demo", "--duration", "600", "--fs", "1", "--json",
          t / "demo.json"], [t / "demo.json"]),
        (["batch", d, "-m", "bias-t", "--out", bad / "fits", "--json", t / "b.json",
          "--pattern", "rec2.csv"], [t / "b.json"]),
    ]


def _check(code, err, bad, absent, t):
    for p in absent:
        assert not p.exists(), f"{p} was written although another output failed"
    assert code == 2, err
    assert len(err) == 1 and err[0].startswith("fogbayes: error: "), err
    assert str(bad) in err[0], err  # the user's path ...
    assert not any(is_temp_name(w.strip("'\":,.()")) for w in err[0].split()), err  # ... only
    assert "Fix: give --" in err[0], err  # the option that takes another path
    assert not [p for p in t.rglob("*") if is_temp_name(p.name)]


@pytest.mark.parametrize("k", range(11))
def test_an_output_under_a_file_stops_the_command_before_any_output(files, tmp_path, capsys, k):
    t = tmp_path / "out"
    t.mkdir()
    bad = files / "rec.csv"  # a file: nothing can be written under it
    argv, absent = _cases(files, t, bad)[k]
    code, err = _run(["-q", *argv], capsys)
    _check(code, err, bad, absent, t)
    assert "is a file, not a folder" in err[0]


@pytest.mark.parametrize("k", [0, 1, 3, 7])
def test_an_output_in_a_read_only_folder_stops_the_command_before_any_output(
        files, tmp_path, capsys, read_only, k):
    t = tmp_path / "out"
    t.mkdir()
    argv, absent = _cases(files, t, read_only)[k]
    code, err = _run(["-q", *argv], capsys)
    _check(code, err, read_only, absent, t)


def test_an_existing_folder_as_the_report_is_refused_before_the_loop(files, tmp_path, capsys):
    t = tmp_path / "out"
    (t / "r.html").mkdir(parents=True)
    code, err = _run(["-q", "loop", files / "rec.csv", "-m", "bias-t", "--json", t / "a.json",
                      "--compensated", t / "c.csv", "--report", t / "r.html"], capsys)
    assert code == 2 and len(err) == 1, err
    assert f"{t / 'r.html'}: is a folder, not a file" in err[0], err
    assert "--report" in err[0], err
    assert not (t / "a.json").exists() and not (t / "c.csv").exists()


def test_a_failure_after_the_first_output_leaves_none(files, tmp_path, capsys, monkeypatch):
    """compensate: the CSV is written, then its summary fails: neither appears, and a file
    of the same name from before is left as it was."""
    import fogbayes.cli.compensate as comp

    def broken(*args, **kwargs):
        raise FogbayesError("the summary failed", file="s.json")

    monkeypatch.setattr(comp, "summary", broken)
    old = tmp_path / "c.csv"
    old.write_text("old\n")
    code, err = _run(["-q", "compensate", files / "rec.csv", "-p", files / "fit.json", "-o",
                      old, "--json", tmp_path / "s.json"], capsys)
    assert code == 2 and err == ["fogbayes: error: s.json: the summary failed"], err
    assert old.read_text() == "old\n"
    assert not (tmp_path / "s.json").exists()
    assert [p.name for p in tmp_path.iterdir()] == ["c.csv"]


def test_all_or_none_renames_every_file_at_the_end_or_none(tmp_path):
    from fogbayes.data.atomic import all_or_none

    a, b = tmp_path / "a.txt", tmp_path / "b.txt"
    with pytest.raises(RuntimeError):
        with all_or_none():
            write_text(a, "A")
            assert not a.exists()  # held back until the block ends
            write_text(b, "B")
            raise RuntimeError("late failure")
    assert sorted(p.name for p in tmp_path.iterdir()) == []
    with all_or_none():
        write_text(a, "A")
        write_text(b, "B")
    assert a.read_text() == "A" and b.read_text() == "B"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.txt", "b.txt"]


@pytest.mark.parametrize("fail_at", [0, 1])
def test_a_signal_during_the_renames_leaves_no_temporary(tmp_path, monkeypatch, fail_at):
    """SIGTERM (here its exception) landing while all_or_none renames its files, before the
    first rename or between two: the files renamed stay (complete), every other temporary
    is removed, and the other final names are untouched."""
    from fogbayes.data import atomic
    from fogbayes.data.atomic import all_or_none

    a, b = tmp_path / "a.txt", tmp_path / "b.txt"
    b.write_text("old")
    real, calls = atomic._rename, []

    def rename(tmp, path):
        calls.append(path)
        if len(calls) - 1 == fail_at:
            raise SystemExit(143)
        real(tmp, path)

    monkeypatch.setattr(atomic, "_rename", rename)
    with pytest.raises(SystemExit):
        with all_or_none():
            write_text(a, "A")
            write_text(b, "B")
    assert sorted(p.name for p in tmp_path.iterdir()) == (["a.txt", "b.txt"] if fail_at else
                                                         ["b.txt"])
    assert b.read_text() == "old" and (not fail_at or a.read_text() == "A")


def test_a_write_refused_by_the_folder_names_the_users_path(read_only):
    """Inside the writer (no check before): the message names c.csv, not .c.tmp-...csv."""
    with pytest.raises(FogbayesError) as info:
        write_text(read_only / "c.csv", "x\n")
    msg = str(info.value)
    assert msg.startswith(f"{read_only / 'c.csv'}: cannot write here"), msg
    assert ".tmp-" not in msg, msg


@pytest.mark.parametrize("command, module, name", [
    ("allan", "fogbayes.plot.allan", "allan_figure"),
    ("arma", "fogbayes.plot.arma", "analysis_figure"),
])
def test_a_figure_that_fails_leaves_no_json(files, tmp_path, capsys, monkeypatch, command,
                                            module, name):
    """allan/arma --json J --plot P: the figure fails after the JSON was written: no J."""
    import importlib

    def broken(*args, **kwargs):
        raise FogbayesError("the figure failed", file="a.png")

    monkeypatch.setattr(importlib.import_module(module), name, broken)
    code, err = _run(["-q", command, files / "rec.csv", "--json", tmp_path / "a.json",
                      "--plot", tmp_path / "a.png"], capsys)
    assert code == 2 and err == ["fogbayes: error: a.png: the figure failed"], err
    assert list(tmp_path.iterdir()) == []


FAKE_CHROMIUM = """#!/bin/sh
# prints the page it is given (a file:// URI, the last argument) as its 'PDF'
for a in "$@"; do
  case "$a" in --print-to-pdf=*) out="${a#--print-to-pdf=}";; esac
  last="$a"
done
/bin/cat "${last#file://}" > "$out"
"""


def test_report_pdf_is_printed_from_the_html_and_both_appear(files, tmp_path, capsys,
                                                             monkeypatch):
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir()
    (bin_dir / "chromium").write_text(FAKE_CHROMIUM)
    (bin_dir / "chromium").chmod(0o755)
    monkeypatch.setenv("PATH", str(bin_dir))
    out = tmp_path / "out"
    code, err = _run(["-q", "report", files / "rec.csv", "--fit", files / "allan.json",
                      "--out", out / "r.html", "--pdf", out / "r.pdf"], capsys)
    assert code == 0, err
    html = (out / "r.html").read_bytes()
    assert html.startswith(b"<!") and (out / "r.pdf").read_bytes() == html
    assert sorted(p.name for p in out.iterdir()) == ["r.html", "r.pdf"]


def test_report_without_a_pdf_printer_writes_no_html(files, tmp_path, capsys, monkeypatch):
    monkeypatch.setenv("PATH", str(tmp_path))  # no chromium here
    out = tmp_path / "out"
    out.mkdir()
    code, err = _run(["-q", "report", files / "rec.csv", "--fit", files / "allan.json",
                      "--out", out / "r.html", "--pdf", out / "r.pdf"], capsys)
    assert code == 2 and len(err) == 1 and "Chromium" in err[0], err
    assert list(out.iterdir()) == []


def test_simulate_truth_that_fails_leaves_no_recording(tmp_path, capsys, monkeypatch):
    import fogbayes.cli.simulate as sim

    def broken(*args, **kwargs):
        raise FogbayesError("the truth failed", file="truth.json")

    monkeypatch.setattr(sim, "write_json", broken)
    code, err = _run(["-q", "simulate", "thermal", "--duration", "600", "--fs", "1", "-o",
                      tmp_path / "s.csv", "--truth", tmp_path / "truth.json"], capsys)
    assert code == 2 and err == ["fogbayes: error: truth.json: the truth failed"], err
    assert list(tmp_path.iterdir()) == []


def test_demo_summary_that_fails_leaves_no_report_or_recording(tmp_path, capsys,
                                                              monkeypatch):
    import fogbayes.cli.demo as demo

    def broken(*args, **kwargs):
        raise FogbayesError("the summary failed", file="demo.json")

    monkeypatch.setattr(demo, "summary_document", broken)
    out = tmp_path / "demo"
    code, err = _run(["-q", "demo", "--out", out, "--duration", "1800", "--fs", "1",
                      "--json", tmp_path / "demo.json"], capsys)
    assert code == 2 and err == ["fogbayes: error: demo.json: the summary failed"], err
    assert [p.name for p in tmp_path.rglob("*")] in ([], ["demo"])  # at most the folder


@pytest.mark.parametrize("name", ["c.csv", ".hidden.json", "x.tar.gz", "noext", "a.b.npz"])
def test_final_path_undoes_temp_path(tmp_path, name):
    from fogbayes.data.atomic import final_path, temp_path

    tmp = temp_path(tmp_path / name)
    assert is_temp_name(tmp.name) and final_path(tmp) == tmp_path / name
    assert final_path(tmp_path / name) == tmp_path / name  # not a temporary: unchanged


def test_an_os_error_on_a_temporary_names_the_users_file(files, tmp_path, capsys,
                                                         monkeypatch):
    """A writer outside atomic_path's own checks (a stream writer, a library) fails on its
    temporary file: the one line names the output the user gave."""
    import fogbayes.cli.fit as fit
    from fogbayes.data.atomic import temp_path

    out = tmp_path / "f.json"

    def refused(*args, **kwargs):
        raise PermissionError(13, "Permission denied", str(temp_path(out)))

    monkeypatch.setattr(fit, "write_json", refused)
    code, err = _run(["-q", "fit", files / "rec.csv", "-m", "bias-t", "--json", out], capsys)
    assert code == 2 and len(err) == 1, err
    assert err[0].startswith(f"fogbayes: error: {out}: Permission denied"), err
    assert ".tmp-" not in err[0], err


def test_a_pdf_printer_that_fails_is_one_line_and_leaves_nothing(files, tmp_path, capsys,
                                                                  monkeypatch):
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir()
    (bin_dir / "chromium").write_text("#!/bin/sh\nexit 3\n")
    (bin_dir / "chromium").chmod(0o755)
    monkeypatch.setenv("PATH", str(bin_dir))
    out = tmp_path / "out"
    out.mkdir()
    code, err = _run(["-q", "report", files / "rec.csv", "--fit", files / "allan.json",
                      "--out", out / "r.html", "--pdf", out / "r.pdf"], capsys)
    assert code == 2 and len(err) == 1, err
    assert err[0].startswith(f"fogbayes: error: {out / 'r.pdf'}"), err
    assert "exit status 3" in err[0] and "drop --pdf" in err[0], err
    assert list(out.iterdir()) == []
