"""``fogbayes fit`` / ``fogbayes compensate`` for the thermal models, end to end."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

import fogbayes.cli.compensate
import fogbayes.cli.fit  # noqa: F401
from fogbayes.cli import main
from fogbayes.data import save
from fogbayes.stats.stability import bias_stability
from fogbayes.simulate import simulate


@pytest.fixture(scope="module")
def run_csv(tmp_path_factory):
    # a short paper-004 profile in Hz with a scale factor (a pulse-output FOG, as in the paper)
    sim = simulate("paper004", seed=3, soak=1200.0, ramp_rate=2.0, unit="Hz", scale_factor=50.0)
    path = tmp_path_factory.mktemp("cli") / "run.csv"
    save(sim.recording, path)
    return path, sim


def test_fit_then_compensate(run_csv, tmp_path, capsys):
    path, sim = run_csv
    fit_json, out_csv = tmp_path / "fit.json", tmp_path / "comp.csv"
    assert main(["fit", str(path), "--model", "thermal", "--orders", "2,1", "--json",
                 str(fit_json)]) == 0
    doc = json.loads(fit_json.read_text())
    assert doc["model"] == "thermal" and doc["converged"] is True
    assert doc["input"]["unit"] == "Hz" and doc["params"]["raw"]["terms"] == ["1", "T", "T^2", "dT/dt"]
    # the Shupe coefficient comes back in deg/h per deg C/min (truth 4.0; 2 % of it is
    # ~10 standard errors here, so this checks units and scaling, not luck)
    assert doc["params"]["raw"]["coef"][3] == pytest.approx(4.0, rel=0.02)
    assert main(["compensate", str(path), "--params", str(fit_json), "--out", str(out_csv)]) == 0
    df = pd.read_csv(out_csv)
    assert list(df.columns) == ["time", "output", "outlier"] and len(df) == sim.recording.n
    assert df["outlier"].dtype == bool
    np.testing.assert_array_equal(df["time"].to_numpy(), sim.recording.time)
    # compensated output stays in Hz; its stability (in deg/h) is the oracle's to 15 %
    comp_deg_h = df["output"].to_numpy() / 50.0 * 3600.0
    oracle = sim.recording.rate("deg/h") - sim.truth.error() * 3600.0 / 50.0
    t = sim.recording.time
    assert bias_stability(comp_deg_h, t) <= 1.15 * bias_stability(oracle, t)


def test_json_to_stdout_and_paper_processing(run_csv, capsys):
    path, _ = run_csv
    assert main(["-q", "fit", str(path), "--model", "bias-t", "--order", "2", "--processing",
                 "paper", "--json", "-"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["model"] == "bias-t" and doc["processing"]["mode"] == "paper"
    assert len(doc["params"]["coef"]) == 3


def test_bad_input_exits_2_with_one_line(run_csv, tmp_path, capsys):
    path, _ = run_csv
    assert main(["fit", str(path), "--model", "thermal", "--orders", "2,two", "--json",
                 str(tmp_path / "f.json")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "orders" in err[0] and "Fix:" in err[0]
    assert main(["fit", str(path), "--model", "thermal", "--temperature", "coil",
                 "--json", str(tmp_path / "f.json")]) == 2
    assert "coil" in capsys.readouterr().err
    bad = tmp_path / "bad.json"
    bad.write_text("{not json")
    assert main(["compensate", str(path), "--params", str(bad), "--out", str(tmp_path / "o.csv")]) == 2
    assert "bad.json" in capsys.readouterr().err


def test_strict_exits_1_when_not_identified(tmp_path):
    # a pure soak: dT/dt never varies, so the thermal model is not identified
    sim = simulate("static", seed=0, duration=600.0, fs=1.0)
    path = tmp_path / "soak.csv"
    save(sim.recording, path)
    fit_json = tmp_path / "f.json"
    assert main(["fit", str(path), "--model", "thermal", "--json", str(fit_json), "--strict"]) == 1
    doc = json.loads(fit_json.read_text())
    assert doc["converged"] is False and "rank deficient" in doc["warnings"][0]
