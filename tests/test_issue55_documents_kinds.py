"""A document of the wrong kind is named for what it is (issue 55).

Each document here is written by the fogbayes command that writes it, then handed to a
reader that wants another kind; the one ``fogbayes: error:`` line must name the file, say
which command wrote it and what the reader wanted, and give a fix naming the right writer.
"""
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest


def _run(cwd: Path, *args):
    return subprocess.run([sys.executable, "-m", "fogbayes", "-q", *args], cwd=cwd,
                          capture_output=True, text=True, timeout=300)


def _ok(cwd, *args):
    res = _run(cwd, *args)
    assert res.returncode == 0, res.stderr
    return res


def _one_line(res) -> str:
    assert res.returncode == 2, res.stderr
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("fogbayes: error:"), res.stderr
    assert "Traceback" not in res.stderr
    return lines[0]


@pytest.fixture(scope="module")
def docs(tmp_path_factory):
    """A short simulated chamber run, its bias-t fit, the compensate summary of applying
    it, its info summary, the simulation truth and a datasheet prior, all written by the CLI."""
    d = tmp_path_factory.mktemp("kinds")
    _ok(d, "simulate", "thermal", "--seed", "3", "--duration", "3600", "--fs", "1",
        "--out", "rec.csv", "--truth", "truth.json")
    _ok(d, "fit", "rec.csv", "-m", "bias-t", "--json", "fit.json")
    _ok(d, "compensate", "rec.csv", "-p", "fit.json", "-o", "comp.csv", "--json", "summary.json")
    _ok(d, "info", "rec.csv", "--json", "info.json")
    _ok(d, "prior", "--arw", "0.05", "--arw-unit", "deg/sqrt(h)", "--rrw", "0.02",
        "--rrw-unit", "deg/h^1.5", "--json", "prior.json")
    return d


def test_compensate_summary_as_params_is_named(docs):
    """The issue's case: compensate's own --json output handed back as --params."""
    line = _one_line(_run(docs, "compensate", "rec.csv", "--params", "summary.json",
                          "-o", "c2.csv"))
    assert "summary.json" in line and "compensate summary" in line
    assert "not a calibration document" in line
    assert "Fix: pass the JSON written by 'fogbayes fit --json'" in line
    assert "newer fogbayes" not in line and "upgrade" not in line
    assert not (docs / "c2.csv").exists()


def test_info_summary_as_report_fit_is_named(docs):
    line = _one_line(_run(docs, "report", "rec.csv", "--fit", "info.json", "-o", "r.html"))
    assert "info.json" in line and "fogbayes info --json" in line
    assert "not a calibration document" in line


def test_fit_document_as_report_loop_is_named(docs):
    """A fit document is no loop: refused, instead of re-running a loop it never recorded."""
    line = _one_line(_run(docs, "report", "rec.csv", "--loop", "fit.json", "-o", "r.html"))
    assert "fit.json" in line and "bias-t fit document" in line
    assert "not a loop document" in line and "fogbayes loop --json" in line
    assert not (docs / "r.html").exists()


def test_truth_as_noise_prior_is_named(docs):
    line = _one_line(_run(docs, "loop", "rec.csv", "-m", "bias-t", "--noise-prior",
                          "truth.json", "--json", "l.json", "--compensated", "lc.csv"))
    assert "truth.json" in line and "simulation truth" in line and "fogbayes simulate" in line
    assert "not a noise prior" in line


def test_fit_document_as_datasheet_prior_is_named(docs):
    line = _one_line(_run(docs, "allan", "rec.csv", "--bayes", "--prior", "fit.json",
                          "--json", "a.json"))
    assert "fit.json" in line and "bias-t fit document" in line
    assert "not a datasheet prior document" in line and "fogbayes prior" in line


def test_the_right_kinds_still_read(docs):
    """The same readers take the kinds they want: a fit as --params, a datasheet prior as
    --noise-prior (its cap is the sheet's RRW x looseness, the top of its 90 % range)."""
    from fogbayes.data.documents import read_calibration
    from fogbayes.loop.noise_prior import read_noise_prior

    assert read_calibration(docs / "fit.json")["model"] == "bias-t"
    assert read_noise_prior(docs / "prior.json").k_max == pytest.approx(0.02 * 3.0)


def test_each_writer_is_recognised(docs):
    """Every document written above is recognised as what its writer wrote."""
    import json

    from fogbayes.data.doc_kinds import document_kind

    kinds = {name: document_kind(json.loads((docs / name).read_text())).key
             for name in ("fit.json", "summary.json", "info.json", "truth.json", "prior.json")}
    assert kinds == {"fit.json": "fit", "summary.json": "compensate_summary",
                     "info.json": "info_summary", "truth.json": "truth", "prior.json": "prior"}
    assert document_kind({"time": [1, 2]}) is None and document_kind([1]) is None
