"""The HTML reports render in real headless Chromium and lead with the answer.

Three report types: the demo report (``fogbayes demo``), the calibration report of a fit
(``fogbayes fit`` + ``fogbayes report --fit``) and the closed-loop report
(:func:`fogbayes.render.loop.loop_report`, what ``fogbayes loop --report`` writes; run here
with one step and few null simulations to stay fast). Each is rendered without console
errors, screenshotted (into docs/screenshots/<type>.png with
FOGBAYES_UPDATE_SCREENSHOTS=1: the screenshots in the docs are the ones these tests take), and its headline block -- the first section -- is read back
from the DOM: before -> after bias stability with intervals that bracket the values and an
improvement equal to 100 (before - after) / before to the shown precision.

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
from pathlib import Path

import numpy as np
import pytest

from fogbayes.cli import main

#: The docs' screenshots are refreshed by these tests when FOGBAYES_UPDATE_SCREENSHOTS=1
#: (otherwise a run would rewrite tracked files with a new date in every picture).
DOC_SHOTS = Path(__file__).resolve().parent.parent / "docs" / "screenshots"
REPORTS = ("demo", "fit", "loop")
WINDOW = (1200, 2400)  # the top of a report: headline, contents, the first section
SHOT_WIDTH = 1000  # px of the committed screenshot (downscaled, 256 colours)


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


@pytest.fixture(scope="module")
def fit_report(demo_report, tmp_path_factory):
    d = tmp_path_factory.mktemp("fit")
    rec = demo_report.parent / "demo_recording.csv"
    assert main(["--quiet", "fit", str(rec), "-m", "thermal", "--json", str(d / "fit.json")]) == 0
    assert main(["--quiet", "report", str(rec), "--fit", str(d / "fit.json"),
                 "--out", str(d / "report.html")]) == 0
    return d / "report.html"


@pytest.fixture(scope="module")
def loop_report(demo_report, tmp_path_factory):
    from fogbayes.data import load
    from fogbayes.loop import run_loop
    from fogbayes.render.loop import loop_report

    d = tmp_path_factory.mktemp("loop")
    rec = load(demo_report.parent / "demo_recording.csv")
    # fast: one step, 20 null series, two candidates, a coarse block grid (about 15 s)
    res = run_loop(rec, "bias-t", max_steps=1, n_sims=20, target_blocks=600,
                   effects=("temperature_rate", "time_drift"))
    assert res.effects == ["temperature_rate"]  # the simulated Shupe term
    return loop_report(res, d / "loop.html", rec=rec, title="Closed loop: demo_recording.csv")


def _run(exe, *args, timeout=120):
    cmd = [exe, "--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars",
           "--enable-logging=stderr", "--v=0", *args]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)


def _save_screenshot(src: Path, dst: Path) -> None:
    """Downscale to SHOT_WIDTH px and 256 colours (Pillow) for the docs; a plain copy
    halved with matplotlib when Pillow is missing."""
    dst.parent.mkdir(parents=True, exist_ok=True)
    try:
        from PIL import Image
    except ImportError:
        from matplotlib.image import imread, imsave

        img = imread(src)[..., :3]
        h, w = (img.shape[0] // 2) * 2, (img.shape[1] // 2) * 2
        imsave(dst, img[:h, :w].reshape(h // 2, 2, w // 2, 2, 3).mean(axis=(1, 3)))
        return
    im = Image.open(src).convert("RGB")
    im = im.resize((SHOT_WIDTH, round(im.height * SHOT_WIDTH / im.width)), Image.LANCZOS)
    im.quantize(colors=256, method=Image.Quantize.FASTOCTREE,
                dither=Image.Dither.NONE).save(dst, optimize=True)


@pytest.mark.parametrize("kind", REPORTS)
def test_report_renders_without_console_errors(kind, request, tmp_path):
    report = request.getfixturevalue(f"{kind}_report")
    exe = _chromium()
    shot = tmp_path / f"{kind}.png"
    r = _run(exe, f"--screenshot={shot}", f"--window-size={WINDOW[0]},{WINDOW[1]}",
             report.as_uri())
    # Chromium logs every console message (errors, failed resources) as INFO:CONSOLE.
    console = [ln for ln in r.stderr.splitlines() if ":CONSOLE" in ln]
    assert console == [], console
    from matplotlib.image import imread

    img = imread(shot)
    assert img.shape[0] == WINDOW[1] and img.shape[1] == WINDOW[0]
    # Not a blank page: a good share of pixels differ from the white background.
    assert (img[..., :3] < 0.9).any(axis=-1).mean() > 0.02
    update = os.environ.get("FOGBAYES_UPDATE_SCREENSHOTS") == "1"
    out = (DOC_SHOTS if update else tmp_path) / f"{kind}.png"
    _save_screenshot(shot, out)
    assert 0 < out.stat().st_size < 400_000


_SUP = str.maketrans("⁻⁰¹²³⁴⁵⁶⁷⁸⁹", "-0123456789")


def _number(text: str) -> tuple[float, float]:
    """A number as the report shows it -> (value, half a unit of its last shown digit)."""
    t = text.replace("−", "-").replace("%", "").strip()
    exp = 0
    if "×10" in t:
        t, e = t.split("×10")
        exp = int(e.translate(_SUP))
    decimals = len(t.split(".")[1]) if "." in t else 0
    return float(t) * 10.0 ** exp, 0.5 * 10.0 ** (exp - decimals)


def _span(html: str, cls: str) -> str:
    m = re.search(rf'<span class="{cls}">([^<]*)</span>', html)
    assert m, f"no <span class=\"{cls}\"> in the headline"
    return m.group(1)


def _interval(html: str, cls: str) -> tuple[float, float]:
    lo, hi = _span(html, cls).strip().rstrip("%").strip().strip("[]").split(",")
    return _number(lo)[0], _number(hi)[0]


@pytest.mark.parametrize("kind", REPORTS)
def test_headline_comes_first_with_before_after_and_intervals(kind, request):
    report = request.getfixturevalue(f"{kind}_report")
    dom = _run(_chromium(), "--dump-dom", report.as_uri()).stdout
    sections = re.findall(r"<section[^>]*>", dom)
    assert sections and 'id="headline"' in sections[0]  # the headline is the first section
    head = dom[dom.index(sections[0]):]
    head = head[:head.index("</section>")]
    assert ">Result<" in head and "Calibrated:" in head and "Model:" in head
    assert 'class="verdict' in head and "Verdict:" in head
    assert "block bootstrap" in head  # the footnote states the method
    row = re.search(r'<tr class="result main">(.*?)</tr>', head, re.S).group(1)
    (b, ub), (a, ua) = _number(_span(row, "bs before")), _number(_span(row, "bs after"))
    imp, _ = _number(_span(row, "bs improvement"))
    assert b > 0 and a > 0
    for val, cls in ((b, "before"), (a, "after"), (imp, "improvement")):
        lo, hi = _interval(row, f"ci {cls}-ci")
        assert lo <= val <= hi, (cls, lo, val, hi)
    # improvement = 100 (before - after) / before, to the precision shown
    tol = 0.05 + 100.0 * (a * ub / b ** 2 + ua / b) + 1e-9
    assert abs(imp - 100.0 * (b - a) / b) <= tol, (b, a, imp)


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


@pytest.fixture(scope="module")
def pool_report(tmp_path_factory):
    """A fleet of eight simulated units, one (unit2) with four times the others' N, pooled
    by the CLI once per run (tests/_pool_fleet.py; tests/test_pool.py checks its document)."""
    from _pool_fleet import pooled_fleet

    return pooled_fleet(tmp_path_factory) / "pool.html"


def test_pool_report_renders_and_leads_with_the_population(pool_report, tmp_path):
    exe = _chromium()
    shot = tmp_path / "pool.png"
    r = _run(exe, f"--screenshot={shot}", f"--window-size={WINDOW[0]},{WINDOW[1]}",
             pool_report.as_uri())
    assert [ln for ln in r.stderr.splitlines() if ":CONSOLE" in ln] == []
    from matplotlib.image import imread

    img = imread(shot)
    assert (img[..., :3] < 0.9).any(axis=-1).mean() > 0.02
    update = os.environ.get("FOGBAYES_UPDATE_SCREENSHOTS") == "1"
    _save_screenshot(shot, (DOC_SHOTS if update else tmp_path) / "pool.png")
    dom = _run(exe, "--dump-dom", pool_report.as_uri()).stdout
    sections = re.findall(r"<section[^>]*>", dom)
    assert sections and 'id="headline"' in sections[0]
    head = dom[dom.index(sections[0]):]
    head = head[:head.index("</section>")]
    assert "population median" in head and "a new unit (90 %)" in head
    assert "Outside the population" in head and "unit2" in head  # the planted outlier
    rows = re.findall(r"<tr><td>([NB])</td><td>[^<]*</td><td>([^<]+)</td><td>\[([^,]+), ([^\]]+)\]", head)
    assert [r[0] for r in rows] == ["N", "B"]
    # the simulated population's N is 0.01 (one unit at 4x); its interval must hold it
    _, v, lo, hi = rows[0]
    assert _number(lo)[0] <= 0.0105 and _number(hi)[0] >= 0.0095 and 0.008 < _number(v)[0] < 0.016
    assert len(re.findall(r'src="data:image/png;base64,', dom)) >= 1
