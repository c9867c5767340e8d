"""``fogbayes batch --task compensate --params DOC``: one calibration applied to a folder, the
same numbers ``fogbayes compensate`` writes for each file; what cannot be applied is refused
in one line (exit 2). Loop documents: tests/test_fit_gls.py."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

import fogbayes.cli as cli
from fogbayes.simulate import simulate


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    d = tmp_path_factory.mktemp("batch_params")
    (d / "runs").mkdir()
    _write(d)
    return d


def _write(d):
    from fogbayes.data import save

    for seed in (1, 2):
        save(simulate("thermal", seed=seed, duration=1800.0, fs=1.0).recording,
             d / "runs" / f"u{seed}.csv")
    assert cli.main(["-q", "fit", str(d / "runs" / "u1.csv"), "-m", "thermal",
                     "--json", str(d / "fit.json")]) == 0


def test_a_fit_document_compensates_every_file_as_compensate_does(folder):
    d = folder
    assert cli.main(["-q", "batch", str(d / "runs"), "-m", "thermal", "--task", "compensate",
                     "--params", str(d / "fit.json"), "--out", str(d / "out")]) == 0
    summary = json.loads((d / "out" / "summary.json").read_text())
    assert [r["status"] for r in summary["rows"]] == ["ok", "ok"]
    assert not list((d / "out").glob("*.fit.json"))  # nothing was fitted
    for seed in (1, 2):
        assert cli.main(["-q", "compensate", str(d / "runs" / f"u{seed}.csv"), "--params",
                         str(d / "fit.json"), "--out", str(d / f"one{seed}.csv")]) == 0
        one = pd.read_csv(d / f"one{seed}.csv", comment="#")
        many = pd.read_csv(d / "out" / f"u{seed}.compensated.csv", comment="#")
        np.testing.assert_array_equal(many["output"], one["output"])
        np.testing.assert_array_equal(many["outlier"], one["outlier"])
    row = summary["rows"][1]  # the second sensor, calibrated by the first one's fit
    assert row["bs_after"] < row["bs_before"] and row["rms_after"] < row["rms_before"]


@pytest.mark.parametrize("extra", [["--task", "fit"], ["-m", "bias-t"],
                                   ["--vectorize"]])
def test_what_cannot_be_applied_is_refused_in_one_line(folder, extra, capsys):
    d = folder
    rc = cli.main(["batch", str(d / "runs"), "-m", "thermal", "--task", "compensate",
                   "--params", str(d / "fit.json"), "--out", str(d / "refused")] + extra)
    err = capsys.readouterr().err
    assert rc == 2 and err.count("\n") == 1 and "--params" in err
    assert not (d / "refused").exists()
