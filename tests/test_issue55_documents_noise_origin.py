"""A report quoting noise from a document says which document and which recording (issue 55).

``fogbayes report a.csv --fit b_adev.json`` shows the N and B of b's Allan analysis; the
verdict and the noise section must say they come from b_adev.json, computed from b.csv,
not from a.csv; a document computed from a.csv itself is quoted as a.csv's own.
"""

from __future__ import annotations

import html
import json
import re

import pytest

from fogbayes import save
from fogbayes.cli import main
from fogbayes.render.html import fmt
from fogbayes.simulate import simulate


@pytest.fixture(scope="module")
def two(tmp_path_factory):
    d = tmp_path_factory.mktemp("origin")
    for name, seed in (("a", 21), ("b", 22)):
        save(simulate("static", duration=1800.0, fs=1.0, seed=seed).recording, d / f"{name}.csv")
        assert main(["-q", "allan", str(d / f"{name}.csv"), "--json",
                     str(d / f"{name}_adev.json")]) == 0
    return d


def _verdict(page: str) -> str:
    m = re.search(r'<p class="verdict[^"]*"><b>Verdict:</b> ([^<]*)</p>', page)
    assert m is not None, "no verdict"
    return html.unescape(m.group(1))


def test_other_recordings_noise_is_named(two):
    out = two / "ra.html"
    assert main(["-q", "report", str(two / "a.csv"), "--fit", str(two / "b_adev.json"),
                 "-o", str(out)]) == 0
    page = out.read_text()
    verdict = _verdict(page)
    n_b = json.loads((two / "b_adev.json").read_text())["fit"]["terms"]["N"]["value"]
    assert f"N = {fmt(n_b)}" in verdict  # the number quoted is b's ...
    assert "from b_adev.json" in verdict and "b.csv" in verdict  # ... and says so
    assert "not of this recording" in verdict
    assert "The noise shown is from b_adev.json, the noise analysis of b.csv" in \
        html.unescape(page)


def test_own_noise_document_is_this_recordings(two):
    """A document computed from this very recording: its numbers are this recording's, and
    the verdict quotes them as such (no other recording is named)."""
    out = two / "rb.html"
    assert main(["-q", "report", str(two / "b.csv"), "--fit", str(two / "b_adev.json"),
                 "-o", str(out)]) == 0
    verdict = _verdict(out.read_text())
    n_b = json.loads((two / "b_adev.json").read_text())["fit"]["terms"]["N"]["value"]
    assert f"N = {fmt(n_b)}" in verdict
    assert "not of this recording" not in verdict and "noise analysis of" not in verdict


def test_public_report_names_the_document(two):
    import fogbayes

    out = fogbayes.report(two / "a.csv", fit=two / "b_adev.json", out=two / "rp.html")
    verdict = _verdict(out.read_text())
    assert "from b_adev.json, the noise analysis of b.csv" in verdict


def _model_line(page: str) -> str:
    m = re.search(r'<p class="what"><b>Model:</b> ([^<]*)</p>', page)
    assert m is not None, "no model line"
    return html.unescape(m.group(1))


def test_fit_document_of_another_run_is_named(tmp_path):
    """Coefficients fitted on another run are applied here: the model line says whose."""
    for name, seed in (("a", 31), ("b", 32)):
        save(simulate("thermal", duration=1800.0, fs=1.0, seed=seed).recording,
             tmp_path / f"{name}.csv")
    assert main(["-q", "fit", str(tmp_path / "b.csv"), "-m", "bias-t", "--json",
                 str(tmp_path / "fit_b.json")]) == 0
    out = tmp_path / "r.html"
    assert main(["-q", "report", str(tmp_path / "a.csv"), "--fit", str(tmp_path / "fit_b.json"),
                 "-o", str(out)]) == 0
    line = _model_line(out.read_text())
    assert "from fit_b.json, the fit of b.csv" in line and "not of this recording" in line


def test_noise_computed_here_names_no_document(two):
    """``--model allan`` computes the noise from this recording: no document is quoted."""
    out = two / "rm.html"
    assert main(["-q", "report", str(two / "a.csv"), "-m", "allan", "-o", str(out)]) == 0
    page = html.unescape(out.read_text())
    assert "document given" not in page and "The noise shown is from" not in page
    assert "N = " in _verdict(page)
