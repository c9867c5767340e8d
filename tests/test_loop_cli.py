"""``fogbayes loop``: files written to the docs/DESIGN.md contract, bad input is exit code 2."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

import fogbayes.cli as cli
import fogbayes.cli.loop  # noqa: F401  (registers the command; the lead wires it in cli/__init__)
from fogbayes.data import Metadata, Recording, save
from fogbayes.loop.testbed import make_record


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    d = tmp_path_factory.mktemp("loop")
    rec = make_record("periodic", seed=2, duration=5400.0, fs=2.0, magnitude=2.0).recording
    save(rec, d / "rec.csv")
    rc = cli.main(["loop", str(d / "rec.csv"), "--model", "bias-t", "--max-steps", "2",
                   "--json", str(d / "loop.json"), "--compensated", str(d / "comp.csv"),
                   "--report", str(d / "loop.html")])
    return rc, d, rec


def test_exit_code_and_json_contract(run):
    rc, d, _ = run
    assert rc == 0
    doc = json.loads((d / "loop.json").read_text())
    assert set(doc) >= {"model", "initial", "steps", "final", "unexplained"}
    assert doc["model"] == "bias-t"
    for key in ("initial", "final"):
        assert set(doc[key]) == {"rms", "bias_stability", "elpd"}
        assert all(isinstance(v, float) for v in doc[key].values())
    assert [s["effect"] for s in doc["steps"]][:1] == ["periodic"]
    s = doc["steps"][0]
    assert s["detail"]["frequency_hz"] == pytest.approx(1 / 600, rel=1e-3)  # simulator default
    assert s["rms_after"] < s["rms_before"]
    assert doc["final"]["rms"] == pytest.approx(doc["steps"][-1]["rms_after"])
    assert all(set(u) == {"kind", "detail"} for u in doc["unexplained"])


def test_compensated_csv_has_every_row(run):
    _, d, rec = run
    df = pd.read_csv(d / "comp.csv")
    assert list(df.columns) == ["time", "output", "outlier"]
    assert len(df) == rec.n
    np.testing.assert_allclose(df["time"], rec.time, rtol=0, atol=1e-9)
    assert df["outlier"].dtype == bool
    # compensated = output - model: what is left is noise of about the white level
    assert np.std(df["output"]) < np.std(rec.output)


def test_report_tells_the_steps(run):
    _, d, _ = run
    html = (d / "loop.html").read_text()
    assert "Closed loop" in html and "Step 1: added periodic" in html and "<img" in html


def test_unknown_model_is_exit_code_2(tmp_path, capsys):
    rec = make_record(None, seed=0, duration=600.0, fs=1.0).recording
    save(rec, tmp_path / "r.csv")
    rc = cli.main(["loop", str(tmp_path / "r.csv"), "--model", "nope", "--json", "-",
                   "--compensated", str(tmp_path / "c.csv")])
    assert rc == 2
    assert "unknown model 'nope'" in capsys.readouterr().err


def test_bias_t_without_temperature_is_exit_code_2(tmp_path, capsys):
    t = np.arange(2000.0)
    rec = Recording(time=t, output=np.zeros(t.size), meta=Metadata(sample_rate=1.0))
    save(rec, tmp_path / "r.csv")
    rc = cli.main(["loop", str(tmp_path / "r.csv"), "--model", "bias-t", "--json", "-",
                   "--compensated", str(tmp_path / "c.csv")])
    assert rc == 2
    err = capsys.readouterr().err
    assert "temperature" in err and "--model allan" in err


def test_unexplained_structure_is_named_on_stderr(tmp_path, capsys):
    """Paper 000's table under the default composite orders: the walk is at its bound and
    the residual holds structure; the status line says so (not only the JSON)."""
    from fogbayes.simulate import simulate

    save(simulate("paper000", seed=0, dwell=20.0).recording, tmp_path / "p000.csv")
    rc = cli.main(["loop", str(tmp_path / "p000.csv"), "--model", "composite", "--max-steps",
                   "0", "--json", str(tmp_path / "l.json"), "--compensated",
                   str(tmp_path / "c.csv")])
    assert rc == 0
    kinds = {u["kind"] for u in json.loads((tmp_path / "l.json").read_text())["unexplained"]}
    assert "noise_model_at_bound" in kinds
    err = capsys.readouterr().err
    assert "unexplained:" in err and "noise_model_at_bound" in err
