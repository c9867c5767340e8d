"""The flat API of ``import fogbayes`` (fit, compensate, run_loop, allan_deviation): the same
results as the modules the command line uses, resolved on first use (importing fogbayes
starts no JAX), and no name that a subpackage would shadow."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

import fogbayes
from fogbayes.simulate import simulate
from fogbayes.stats.allan import allan_deviation
from fogbayes.thermal.workflow import compensate_recording, fit_recording


def test_import_fogbayes_starts_no_jax():
    code = "import sys, fogbayes; print('jax' in sys.modules, 'numpyro' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["False", "False"]


def test_flat_names_are_the_workflow_functions():
    rec = simulate("thermal", seed=3, duration=3600.0, fs=1.0).recording
    doc = fogbayes.fit(rec, model="thermal", orders="2,1")
    ref = fit_recording(rec, model="thermal", orders="2,1")
    np.testing.assert_array_equal(doc["params"]["coef"], ref["params"]["coef"])
    comp = fogbayes.compensate(rec, doc)
    np.testing.assert_array_equal(comp["output"], compensate_recording(rec, ref)["output"])
    assert fogbayes.allan_deviation is allan_deviation
    assert callable(fogbayes.run_loop)
    with pytest.raises(fogbayes.FogbayesError, match="nothing to compensate"):
        fogbayes.compensate(rec, {"model": "allan"})
    with pytest.raises(AttributeError):
        fogbayes.no_such_name  # noqa: B018
    static = simulate("static", seed=1, duration=600.0, fs=10.0).recording
    with pytest.raises(fogbayes.FogbayesError, match="candidates"):  # never silently ignored
        fogbayes.fit(static, model="arma", orders="1,1")


def test_every_public_name_resolves_and_no_subpackage_is_shadowed():
    import importlib
    import pkgutil

    subpackages = {m.name for m in pkgutil.iter_modules(fogbayes.__path__)}
    # no public name is a subpackage: importing fogbayes.x.y would rebind fogbayes.x
    assert set(fogbayes.__all__) & subpackages == set()
    importlib.import_module("fogbayes.render.sections")
    assert fogbayes.report.__module__ == "fogbayes.workflow.report"
    for name in fogbayes.__all__:
        assert getattr(fogbayes, name) is not None
    assert importlib.import_module("fogbayes.simulate").simulate is simulate


def _page_text(path) -> str:
    """The report's text without its generation time and the embedded images' bytes."""
    import re

    page = path.read_text()
    page = re.sub(r"\d{4}-\d{2}-\d{2} \d{2}:\d{2} UTC", "", page)
    return re.sub(r'src="data:image/[^"]*"', "", page)


def test_fogbayes_report_writes_what_the_command_writes(tmp_path):
    """``fogbayes.report(rec, doc, out)`` == ``fogbayes report REC --fit doc.json --out``:
    the same HTML (up to the time stamp and the figures' bytes), from a document in
    memory or a path; a document of the wrong kind ends in the FogbayesError the command
    prints."""
    import json

    from fogbayes.cli import main

    rec = simulate("thermal", seed=3, duration=3600.0, fs=1.0).recording
    csv = tmp_path / "rec.csv"
    fogbayes.save(rec, csv)
    rec = fogbayes.load(csv)
    doc = fogbayes.fit(rec, model="thermal", orders="2,1")
    (tmp_path / "fit.json").write_text(json.dumps(json.loads(json.dumps(
        doc, default=lambda o: o.tolist() if hasattr(o, "tolist") else float(o)))))
    assert main(["-q", "report", str(csv), "--fit", str(tmp_path / "fit.json"),
                 "--out", str(tmp_path / "cli.html")]) == 0
    api = fogbayes.report(rec, doc, tmp_path / "api.html")
    assert api == tmp_path / "api.html"
    assert _page_text(api) == _page_text(tmp_path / "cli.html")
    by_path = fogbayes.report(csv, tmp_path / "fit.json", tmp_path / "path.html")
    assert _page_text(by_path) == _page_text(tmp_path / "cli.html")
    with pytest.raises(fogbayes.FogbayesError):
        fogbayes.report(rec, {"model": "thermal", "schema": "no-such-schema"}, tmp_path / "x.html")
