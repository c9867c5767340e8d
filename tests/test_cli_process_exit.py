"""The ``fogbayes`` script ends its process without the interpreter's teardown
(:func:`fogbayes.cli.run`), and loses nothing a normal exit keeps: the exit code, every byte
written to stdout, exit handlers (which may still print), non-daemon threads' work."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import fogbayes
from fogbayes.simulate import simulate


def _buffered() -> dict:
    """The environment with stdout block-buffered, as it is on a pipe by default: what the
    process must flush itself before it ends."""
    env = dict(os.environ)
    env.pop("PYTHONUNBUFFERED", None)
    return env


def test_a_document_on_stdout_arrives_whole_and_the_exit_code_is_kept(tmp_path):
    rec = simulate("static", seed=3, duration=600.0, fs=10.0).recording
    src = fogbayes.save(rec, tmp_path / "static.csv")
    ok = subprocess.run([sys.executable, "-m", "fogbayes", "-q", "info", str(src), "--json",
                         "-"], capture_output=True, text=True, env=_buffered())
    assert ok.returncode == 0, ok.stderr
    doc = json.loads(ok.stdout)  # the whole document: an unflushed buffer would be lost
    assert doc["n"] == 6000 and doc["sensor_id"] == rec.meta.sensor_id
    bad = subprocess.run([sys.executable, "-m", "fogbayes", "allan", str(tmp_path / "none.csv")],
                         capture_output=True, text=True, env=_buffered())
    assert bad.returncode == 2
    assert bad.stderr.startswith("fogbayes: error:") and "Traceback" not in bad.stderr


_CODE = """
import atexit, sys, threading, time
from pathlib import Path
from fogbayes.cli import run
out = Path(sys.argv[1])
def late():
    time.sleep(0.3)
    out.write_text("thread done")
threading.Thread(target=late).start()
atexit.register(lambda: print("exit handler ran", flush=False))
sys.argv = ["fogbayes", "--help"]
run()
print("never reached")
"""


def test_exit_handlers_run_and_threads_finish_before_the_process_ends(tmp_path):
    marker = tmp_path / "thread.txt"
    r = subprocess.run([sys.executable, "-c", _CODE, str(marker)], capture_output=True,
                       text=True, env=_buffered())
    assert r.returncode == 0, r.stderr
    assert "Usage" in r.stdout and r.stdout.rstrip().endswith("exit handler ran")
    assert "never reached" not in r.stdout
    assert marker.read_text() == "thread done"
