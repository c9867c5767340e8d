"""The HTML report renders in real headless Chromium without console errors.

Chromium (Debian's ``chromium`` package) is installed by the README's test command. Outside
CI a missing browser skips these tests with the reason; under CI (``CI`` set) it fails.
"""

from __future__ import annotations

import base64
import io
import os
import re
import shutil
import subprocess

import numpy as np
import pytest

from fogbayes.cli import main


def _chromium() -> str:
    exe = shutil.which("chromium") or shutil.which("chromium-browser") or shutil.which("google-chrome")
    if exe is None:
        msg = "headless Chromium not found (apt-get install chromium)"
        if os.environ.get("CI"):
            pytest.fail(msg + "; the README test command installs it")
        pytest.skip(msg)
    return exe


@pytest.fixture(scope="module")
def demo_report(tmp_path_factory):
    out = tmp_path_factory.mktemp("demo")
    assert main(["--quiet", "demo", "--out", str(out), "--duration", "3600", "--fs", "1"]) == 0
    return out / "report.html"


def _run(exe, *args, timeout=120):
    cmd = [exe, "--headless", "--no-sandbox", "--disable-gpu", "--enable-logging=stderr", "--v=0",
           *args]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)


def test_report_renders_without_console_errors(demo_report, tmp_path):
    exe = _chromium()
    shot = tmp_path / "report.png"
    r = _run(exe, f"--screenshot={shot}", "--window-size=1200,4000", demo_report.as_uri())
    # Chromium logs every console message (errors, failed resources) as INFO:CONSOLE.
    console = [ln for ln in r.stderr.splitlines() if ":CONSOLE" in ln]
    assert console == [], console
    from matplotlib.image import imread

    img = imread(shot)
    assert img.shape[0] >= 3000 and img.shape[1] == 1200
    # Not a blank page: a good share of pixels differ from the white background.
    assert (img[..., :3] < 0.9).any(axis=-1).mean() > 0.02


def test_report_dom_has_every_section_with_figures_and_tables(demo_report):
    exe = _chromium()
    dom = _run(exe, "--dump-dom", demo_report.as_uri()).stdout
    for title in ("Recording", "Fitted model: bias-t", "Fitted model: thermal", "Residuals",
                  "Compensation", "Allan deviation"):
        assert f">{title}" in dom
    assert dom.count("<table") >= 3
    images = re.findall(r'src="data:image/png;base64,([^"]+)"', dom)
    assert len(images) >= 3
    from matplotlib.image import imread

    for b64 in images:  # every embedded figure is a decodable, non-empty PNG
        img = imread(io.BytesIO(base64.b64decode(b64)), format="png")
        assert img.shape[0] > 100 and np.ptp(img[..., :3]) > 0.5
