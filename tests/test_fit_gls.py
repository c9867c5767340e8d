"""``fogbayes fit --estimator gls`` is ``fogbayes loop --max-steps 0``: one estimator, one
document, read by ``compensate``; the loop's orders take the fit's grammar."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

import fogbayes.cli as cli
from fogbayes.data import save
from fogbayes.loop.context import make_context
from fogbayes.loop.bases import ModelNameError, base_terms, parse_orders
from fogbayes.loop.testbed import make_record


@pytest.fixture(scope="module")
def record(tmp_path_factory):
    d = tmp_path_factory.mktemp("gls")
    rec = make_record("temperature_rate", seed=3, duration=2400.0, fs=1.0).recording
    save(rec, d / "rec.csv")
    return d, rec


@pytest.fixture(scope="module")
def both(record):
    d, _ = record
    rc_fit = cli.main(["-q", "fit", str(d / "rec.csv"), "-m", "thermal", "--orders", "2,1",
                       "--estimator", "gls", "--json", str(d / "fit.json")])
    rc_loop = cli.main(["-q", "loop", str(d / "rec.csv"), "-m", "thermal", "--orders", "2,1",
                        "--max-steps", "0", "--json", str(d / "loop.json"),
                        "--compensated", str(d / "loop.csv")])
    assert (rc_fit, rc_loop) == (0, 0)
    return json.loads((d / "fit.json").read_text()), json.loads((d / "loop.json").read_text())


def test_fit_gls_gives_the_coefficients_of_the_loop_with_no_step(both):
    fit, loop = both
    a, b = fit["calibration"], loop["calibration"]
    assert a["terms"] == b["terms"]
    kinds = [(t["kind"], t["params"].get("powers")) for t in a["terms"]]
    assert kinds == [("intercept", None), ("tpoly", [1, 2]), ("rate_poly", [1])]  # "2,1"
    np.testing.assert_allclose(a["coefficients"], b["coefficients"], rtol=1e-8, atol=0)
    np.testing.assert_allclose(a["covariance"], b["covariance"], rtol=1e-8, atol=1e-300)
    assert fit["steps"] == [] and fit["schema"] == "fogbayes.loop/1"
    # the same terms by two estimators are "not worse" than each other: no false warning
    assert fit["holdout"]["final_not_worse_than_plain_fit"] is True
    assert not any("worse than" in w for w in fit.get("warnings", []))


def test_bias_t_at_the_fits_default_order_is_the_loop_at_that_order(record):
    # `fogbayes fit -m bias-t --estimator gls` and the loop with no step, neither given
    # orders, take the one default (3) and write the same coefficients
    d, _ = record
    assert cli.main(["-q", "fit", str(d / "rec.csv"), "-m", "bias-t", "--estimator", "gls",
                     "--json", str(d / "fit_bt.json")]) == 0
    assert cli.main(["-q", "loop", str(d / "rec.csv"), "-m", "bias-t",
                     "--max-steps", "0", "--json", str(d / "loop_bt.json"),
                     "--compensated", str(d / "loop_bt.csv")]) == 0
    a, b = (json.loads((d / n).read_text())["calibration"] for n in ("fit_bt.json", "loop_bt.json"))
    assert a["terms"] == b["terms"]
    assert [(t["kind"], t["params"].get("powers")) for t in a["terms"]] == [
        ("intercept", None), ("tpoly", [1, 2, 3])]
    np.testing.assert_allclose(a["coefficients"], b["coefficients"], rtol=1e-8, atol=0)


def test_compensate_reads_the_gls_fit_like_the_loop_writes_it(record, both):
    d, rec = record
    rc = cli.main(["-q", "compensate", str(d / "rec.csv"), "--params", str(d / "fit.json"),
                   "--out", str(d / "comp.csv")])
    assert rc == 0
    comp, loop = pd.read_csv(d / "comp.csv"), pd.read_csv(d / "loop.csv")
    assert len(comp) == rec.n
    np.testing.assert_allclose(comp["output"], loop["output"], rtol=0, atol=1e-9)


@pytest.mark.parametrize("extra", [["--orders", "auto"], ["--orders", "1-3"], ["--bayes"],
                                   ["-O", "n_sigma=4"], ["--estimator", "wls"],
                                   ["-m", "allan"]])
def test_what_the_gls_path_cannot_take_is_refused_in_one_line(record, extra, capsys):
    d, _ = record
    args = ["fit", str(d / "rec.csv"), "-m", "thermal", "--estimator", "gls",
            "--json", str(d / "x.json")]
    rc = cli.main(args + extra)  # the later -m / --estimator wins
    err = capsys.readouterr().err
    assert rc == 2 and "Traceback" not in err
    assert err.count("\n") == 1 and "fogbayes: error:" in err
    assert not (d / "x.json").exists()


def test_the_loops_thermal_orders_read_like_the_fits(record):
    _, rec = record
    assert parse_orders("thermal", "2") == (2, 2)  # "n": T and dT/dt both n, as fit
    assert parse_orders("thermal", "3,1") == (3, 1)
    assert parse_orders("thermal", None) == (2, 2)
    with pytest.raises(ModelNameError):
        parse_orders("thermal", "1,2,3")
    with pytest.raises(ModelNameError):
        parse_orders("bias-t", "2,1")
    ctx = make_context(rec)
    assert [t.kind for t in base_terms(ctx, "thermal", "2,0")] == ["intercept", "tpoly"]
    assert base_terms(ctx, "thermal", "2,0") == base_terms(ctx, "bias-t", "2")


def test_batch_applies_the_document_to_a_folder_like_compensate(record, both, tmp_path):
    d, rec = record
    runs = tmp_path / "runs"
    runs.mkdir()
    save(rec, runs / "a.csv")
    save(make_record("temperature_rate", seed=4, duration=1800.0, fs=1.0).recording,
         runs / "b.csv")
    rc = cli.main(["-q", "batch", str(runs), "-m", "thermal", "--task", "compensate",
                   "--params", str(d / "fit.json"), "--out", str(tmp_path / "out")])
    assert rc == 0
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert [r["status"] for r in summary["rows"]] == ["ok", "ok"]
    assert summary["options"]["params"]["schema"] == "fogbayes.loop/1"
    for row in summary["rows"]:
        name = row["file"].rsplit("/", 1)[-1]
        assert cli.main(["-q", "compensate", str(runs / name), "--params", str(d / "fit.json"),
                         "--out", str(tmp_path / f"one_{name}")]) == 0
        one = pd.read_csv(tmp_path / f"one_{name}")
        many = pd.read_csv(tmp_path / "out" / row["outputs"]["compensated"])
        np.testing.assert_array_equal(many["output"], one["output"])
        assert row["rms_after"] < row["rms_before"]
