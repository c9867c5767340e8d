"""Ctrl-C (SIGINT) ends a command with one line, ``fogbayes: interrupted``, and exit code 130."""
import subprocess
import sys
import textwrap

# A command that waits (as a long fit does) run through the real entry point, interrupted
# by a SIGINT to its own process after 1 s: what Ctrl-C in a terminal sends.
SCRIPT = textwrap.dedent("""
    import os, signal, sys, threading, time
    from fogbayes.cli import app, main

    @app.command("nap")
    def nap():
        time.sleep(60)

    threading.Timer(1.0, os.kill, (os.getpid(), signal.SIGINT)).start()
    sys.exit(main(["nap"]))
""")


def test_ctrl_c_prints_one_line_and_exits_130():
    res = subprocess.run([sys.executable, "-c", SCRIPT], capture_output=True, text=True,
                         timeout=60)
    assert res.returncode == 130, res.stderr
    assert res.stderr.strip().splitlines() == [
        "fogbayes: interrupted; unfinished outputs were not written"], res.stderr
