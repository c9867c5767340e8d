"""`fogbayes batch`: a fleet on a local Dask cluster equals the in-process run; bad files are
error rows; bad input is exit code 2; the vectorised fit equals the per-recording workflow.

The fleet is three 20 min, 1 Hz simulated thermal tests (heating/cooling, quadratic bias in
T, FOG-like noise) plus one corrupt CSV, written once per module; the in-process run is made
once and is the reference of the Dask and vectorised runs.
"""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

from fogbayes.support.jsonable import to_jsonable
from fogbayes.cli import main
from fogbayes.data import load
from fogbayes.data.io import save
from fogbayes.simulate.scenarios import simulate
from fogbayes.workflow import workflow_for

GOOD = ("g0.csv", "g1.csv", "g2.csv")
BAD = "corrupt.csv"


@pytest.fixture(scope="module")
def fleet(tmp_path_factory):
    d = tmp_path_factory.mktemp("fleet")
    for s, name in enumerate(GOOD):
        save(simulate("thermal", seed=s, duration=1200.0, fs=1.0, sensor_id=f"g{s}").recording,
             d / name)
    (d / BAD).write_text("time,output,temperature\n0,1,20\n1,abc,20\n2,3,20\n")
    return d


def _run(args, capsys):
    code = main(["batch", *map(str, args), "--quiet"])
    return code, capsys.readouterr()


def _summary(out):
    return json.loads((out / "summary.json").read_text())


@pytest.fixture(scope="module")
def local(fleet, tmp_path_factory):
    out = tmp_path_factory.mktemp("local")
    code = main(["batch", str(fleet), "--model", "bias-t", "--out", str(out), "--quiet"])
    return code, out, _summary(out)


def _rows(summary):
    return [{k: v for k, v in r.items() if k != "seconds"} for r in summary["rows"]]


def _close(a, b, rtol, atol, where="doc"):
    """Recursive comparison of two JSON documents: same keys and strings, numbers close."""
    if isinstance(a, dict):
        assert set(a) == set(b), (where, set(a) ^ set(b))
        for k in a:
            _close(a[k], b[k], rtol, atol, f"{where}.{k}")
    elif isinstance(a, list):
        assert len(a) == len(b), where
        for i, (x, y) in enumerate(zip(a, b)):
            _close(x, y, rtol, atol, f"{where}[{i}]")
    elif isinstance(a, float) and not isinstance(a, bool):
        assert b == pytest.approx(a, rel=rtol, abs=atol), where
    else:
        assert a == b, where


def test_in_process_fit_equals_the_workflow(fleet, local):
    # the batch `fit` task writes exactly what the per-recording workflow returns
    _, out, _ = local
    doc = json.loads((out / "g1.fit.json").read_text())
    ref = to_jsonable(workflow_for("bias-t").fit_recording(load(fleet / "g1.csv"), model="bias-t"))
    assert doc == ref


def test_corrupt_file_is_an_error_row_and_exit_1(fleet, local):
    code, out, summary = local
    assert code == 1  # one recording failed
    assert [r["file"] for r in summary["rows"]] == [str(fleet / n) for n in sorted((BAD, *GOOD))]
    bad = summary["rows"][0]
    assert bad["status"] == "error" and str(fleet / BAD) in bad["error"]
    assert "'abc' is not a number" in bad["error"] and "row 1" in bad["error"]
    ok = summary["rows"][1:]
    assert all(r["status"] == "ok" and r["converged"] for r in ok)
    assert summary["n_ok"] == 3 and summary["n_error"] == 1 and summary["engine"] == "local"
    assert sorted(p.name for p in out.glob("*.fit.json")) == [f"{n[:-4]}.fit.json" for n in GOOD]
    # the thermal drift is removed: 1 s bias stability improves on every good recording
    # (simulated quadratic bias of ~0.2 deg/h over the run against 0.3 deg/h noise)
    assert all(r["bs_after"] < r["bs_before"] for r in ok)


def test_dask_cluster_of_two_workers_equals_in_process(fleet, local, tmp_path, capsys):
    """The issue's acceptance test: `fogbayes batch` on a local Dask cluster of 2 workers."""
    code_local, out_local, ref = local
    out = tmp_path / "dask"
    code, _ = _run([fleet, "--model", "bias-t", "--out", out, "--engine", "dask",
                    "--workers", "2"], capsys)
    summary = _summary(out)
    assert code == code_local == 1
    assert summary["engine"] == "dask" and summary["workers"] == 2
    assert _rows(summary) == _rows(ref)  # same rows, same order, same numbers
    for name in GOOD:
        a = json.loads((out_local / name.replace(".csv", ".fit.json")).read_text())
        b = json.loads((out / name.replace(".csv", ".fit.json")).read_text())
        # workers import fogbayes (float64) and run the same code on the same CPU: the
        # documents are identical (measured: byte-identical files); 1e-12 allows only for
        # a different BLAS thread count in the worker processes
        _close(a, b, rtol=1e-12, atol=0.0)
        assert a["params"]["coef"] == pytest.approx(b["params"]["coef"], rel=1e-12, abs=0)


@pytest.mark.parametrize("args, words", [
    (["missing"], ("no such folder", "Fix:")),
    (["empty"], ("no recordings match '*.csv'", "--pattern")),
    (["fleet", "--model", "nonsense"], ("unknown model 'nonsense'", "bias-t")),
    (["fleet", "--task", "dance"], ("unknown task 'dance'", "loop")),
    (["fleet", "--address", "tcp://127.0.0.1:9"], ("--address", "--engine dask")),
])
def test_bad_input_is_exit_2_with_one_line(fleet, tmp_path, capsys, args, words):
    (tmp_path / "empty").mkdir()
    folder = {"missing": tmp_path / "missing", "empty": tmp_path / "empty", "fleet": fleet}[args[0]]
    model = [] if "--model" in args else ["--model", "bias-t"]
    code, cap = _run([folder, *model, *args[1:], "--out", tmp_path / "out"], capsys)
    err = cap.err.strip().splitlines()
    assert code == 2 and len(err) == 1 and err[0].startswith("fogbayes: error: ")
    assert all(w in err[0] for w in words) and "Traceback" not in cap.err
    assert not (tmp_path / "out" / "summary.json").exists()


def test_vectorize_equals_per_recording_fits(fleet, local, tmp_path, capsys):
    _, out_local, _ = local
    out = tmp_path / "vec"
    code, _ = _run([fleet, "--model", "bias-t", "--out", out, "--vectorize", "--task",
                    "compensate"], capsys)
    summary = _summary(out)
    assert code == 1 and summary["vectorized"] and summary["n_ok"] == 3  # the corrupt file
    assert summary["rows"][0]["status"] == "error" and BAD in summary["rows"][0]["error"]
    for name in GOOD:
        stem = name[:-4]
        ref = json.loads((out_local / f"{stem}.fit.json").read_text())
        doc = json.loads((out / f"{stem}.fit.json").read_text())
        assert doc.pop("vectorized") is True
        # same blocks, outliers and bases; only the solver differs (normal equations vs QR
        # in the scaled basis, cond(X) ~ 10 so cond(G) ~ 1e2): measured agreement ~1e-14;
        # absolute 1e-12 deg/h for values that are sums of ~1e3 terms of order 1
        _close(ref, doc, rtol=1e-9, atol=1e-12)
        c, c_ref = np.array(doc["params"]["coef"]), np.array(ref["params"]["coef"])
        assert np.max(np.abs(c - c_ref)) <= 1e-9 * np.max(np.abs(c_ref))
        # the compensated CSV is the per-recording compensation with the reference fit
        comp = pd.read_csv(out / f"{stem}.compensated.csv")
        cols = workflow_for("bias-t").compensate_recording(load(fleet / name), ref)
        np.testing.assert_allclose(comp["output"], cols["output"], rtol=0, atol=1e-9)
        assert (comp["outlier"].to_numpy() == cols["outlier"]).all()


def test_vectorized_thermal_model_with_the_workflows_qr_solver(fleet):
    from fogbayes.batch import fit_vectorized

    # thermal (T and dT/dt), the QR solver of the workflow (the normal equations are the
    # bias-t CLI test's); two recordings make a batch, a third only adds time
    recs = [load(fleet / n) for n in GOOD[:2]]
    refs = [workflow_for("thermal").fit_recording(r, model="thermal") for r in recs]
    assert all(r["outliers"]["count"] for r in refs)  # the Pauta refit path is exercised
    for ref, doc in zip(refs, fit_vectorized(recs, model="thermal", solver="qr")):
        doc = to_jsonable(doc)
        doc.pop("vectorized")
        _close(to_jsonable(ref), doc, rtol=1e-9, atol=1e-12)  # tolerance: see above


def test_vectorize_refuses_mixed_lengths(fleet, tmp_path, capsys):
    for s, dur in enumerate((600.0, 700.0)):
        save(simulate("thermal", seed=s, duration=dur, fs=1.0).recording, tmp_path / f"r{s}.csv")
    code, cap = _run([tmp_path, "--model", "bias-t", "--out", tmp_path / "o", "--vectorize"], capsys)
    assert code == 2 and "one length and sampling" in cap.err and "r1.csv" in cap.err


def test_loop_task_writes_what_run_loop_returns(tmp_path):
    from fogbayes.batch import run_one
    from fogbayes.loop import run_loop

    # 10 min and no step: the contract of the files, not the loop's statistics (tested in
    # test_loop_*), at a few seconds
    path = save(simulate("thermal", seed=5, duration=600.0, fs=1.0).recording, tmp_path / "a.csv")
    row = run_one(path, model="bias-t", task="loop", out_dir=tmp_path / "out",
                  options={"max_steps": 0})
    assert row["status"] == "ok", row
    ref = run_loop(load(path), "bias-t", max_steps=0)
    doc = json.loads((tmp_path / "out" / row["outputs"]["loop"]).read_text())
    assert doc == json.loads(json.dumps(to_jsonable(ref.to_json())))
    assert row["rms_before"] == ref.initial.rms and row["rms_after"] == ref.final.rms
    comp = pd.read_csv(tmp_path / "out" / row["outputs"]["compensated"])
    np.testing.assert_array_equal(comp["output"], ref.compensated["output"])  # %.17g: exact


def test_vectorized_two_clocks_and_emptied_blocks_equal_the_workflow():
    from fogbayes.batch import fit_vectorized

    # 1 Hz with 1 s blocks: every Pauta-flagged sample empties its block (weight 0 in the
    # stacked fit, dropped by the workflow); two clock groups of 3 and 2 recordings
    recs = [simulate("thermal", seed=s, duration=1200.0, fs=1.0, sensor_id=f"s{s}").recording
            for s in range(5)]
    recs[3:] = [r.replace(time=r.time + 0.5) for r in recs[3:]]
    docs = fit_vectorized(recs, model="thermal")
    assert sum(d["outliers"]["count"] for d in docs) > 0
    assert len({d["fit"]["n_blocks"] for d in docs}) > 1  # emptied blocks differ by sensor
    for rec, doc in zip(recs, docs):
        ref = to_jsonable(workflow_for("thermal").fit_recording(rec, model="thermal"))
        doc = to_jsonable(doc)
        assert doc.pop("vectorized") is True
        _close(ref, doc, rtol=1e-9, atol=1e-12)  # tolerance: see the CLI test above


def test_vectorized_reports_an_unfittable_recording_and_fits_the_others():
    from fogbayes.batch import fit_vectorized

    # one recording without a temperature channel: the batched preparation fails, the
    # recordings are prepared one by one, the bad one is reported, the others still equal
    # the workflow's documents (recordings stacked from per-recording blocks)
    recs = [simulate("thermal", seed=s, duration=1200.0, fs=1.0, sensor_id=f"s{s}").recording
            for s in range(4)]
    recs[2] = recs[2].replace(temperatures=np.zeros((recs[2].n, 0)), temperature_names=())
    errors = []
    docs = fit_vectorized(recs, model="thermal", on_error=lambda i, e: errors.append((i, e)))
    assert [i for i, _ in errors] == [2] and "temperature" in str(errors[0][1])
    assert docs[2] is None
    for rec, doc in zip(recs, docs):
        if doc is None:
            continue
        ref = to_jsonable(workflow_for("thermal").fit_recording(rec, model="thermal"))
        doc = to_jsonable(doc)
        assert doc.pop("vectorized") is True
        _close(ref, doc, rtol=1e-9, atol=1e-12)
    with pytest.raises(Exception, match="temperature"):  # without on_error: raised
        fit_vectorized(recs, model="thermal")
