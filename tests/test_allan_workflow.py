"""The ``allan`` workflow, its JSON document, the figure and the ``fogbayes allan`` command."""

from __future__ import annotations

import json

import numpy as np
import pytest

from fogbayes import Recording
from fogbayes.data import Metadata, save
from fogbayes.errors import FogbayesError
from fogbayes.simulate.noise import allan_noise
from fogbayes.stats.allan import allan_deviation
from fogbayes.allan.workflow import AllanInputError, compensate_recording, fit_recording

FS = 10.0
TRUTH = dict(Q=0.19, N=0.01, B=0.165, K=0.66)  # crossovers at 0.3, 30 and 300 s


@pytest.fixture(scope="module")
def rate_deg_h():
    return allan_noise(2**14, FS, seed=7, **TRUTH)


def _recording(rate_deg_h, unit="deg/h", drop=slice(3000, 3050)):
    t = np.arange(rate_deg_h.size) / FS
    keep = np.ones(rate_deg_h.size, bool)
    keep[drop] = False
    scale = {"deg/h": 1.0, "deg/s": 1 / 3600.0, "rad/s": np.pi / 180 / 3600}[unit]
    return Recording(time=t[keep], output=rate_deg_h[keep] * scale, unit=unit,
                     meta=Metadata(sensor_id="sim-7", sample_rate=FS))


@pytest.fixture(scope="module")
def doc_deg_h(rate_deg_h):
    return fit_recording(_recording(rate_deg_h))


def test_document_has_the_issue_schema_in_canonical_units(doc_deg_h, rate_deg_h):
    doc = doc_deg_h
    for key in ("n", "fs", "unit", "tau", "adev", "adev_low", "adev_high", "edf", "fit"):
        assert key in doc
    assert doc["unit"] == "deg/h" and doc["model"] == "allan" and doc["fs"] == FS
    units = {t: e["unit"] for t, e in doc["fit"]["terms"].items()}
    assert units == {"Q": "arcsec", "N": "deg/sqrt(h)", "B": "deg/h", "K": "deg/h^1.5",
                     "R": "deg/h^2"}
    q = doc["fit"]["terms"]["Q"]
    assert q["value_urad"] == pytest.approx(q["value"] * 4.8481368, rel=1e-7)
    # the gap is NaN on the grid: the deviations are those of the record with NaN samples
    y = rate_deg_h.copy()
    y[3000:3050] = np.nan
    ref = allan_deviation(y, FS, ci=0.9)
    np.testing.assert_allclose(doc["adev"], ref.dev, rtol=1e-12)
    assert doc["gaps"]["missing_samples"] == 50 and "excluded" in doc["gaps"]["note"]
    assert np.all(np.asarray(doc["adev_low"]) < doc["adev"])
    json.dumps(__import__("fogbayes.cli._common", fromlist=["x"]).to_jsonable(doc))


def test_gls_fit_recovers_the_simulated_terms(doc_deg_h):
    terms = doc_deg_h["fit"]["terms"]
    for name in ("Q", "N", "B"):
        e = terms[name]
        assert e["low"] <= TRUTH[name] <= e["high"], (name, e)  # 90 % intervals
    assert terms["N"]["high"] / terms["N"]["low"] < 1.1  # N is pinned by 16k samples
    assert doc_deg_h["converged"]


@pytest.mark.parametrize("unit", ["deg/s", "rad/s"])
def test_results_do_not_depend_on_the_input_unit(rate_deg_h, doc_deg_h, unit):
    doc = fit_recording(_recording(rate_deg_h, unit))
    assert doc["input_unit"] == unit
    np.testing.assert_allclose(doc["adev"], doc_deg_h["adev"], rtol=1e-9)
    for t, e in doc["fit"]["terms"].items():
        assert e["value"] == pytest.approx(doc_deg_h["fit"]["terms"][t]["value"], rel=1e-6)


def test_bad_input_and_compensation_are_refused(rate_deg_h, doc_deg_h):
    rec = _recording(rate_deg_h)
    with pytest.raises(FogbayesError, match="nothing to compensate"):
        compensate_recording(rec, doc_deg_h)
    with pytest.raises(FogbayesError, match="unknown option"):
        fit_recording(rec, frobnicate=1)
    with pytest.raises(FogbayesError, match="not 'thermal'"):
        fit_recording(rec, model="thermal")
    t = np.arange(2000) / FS
    t[700:] += 0.037  # a jitter of a third of a sample period from row 700 on
    bad = Recording(time=t, output=np.zeros(2000), unit="deg/h")
    with pytest.raises(AllanInputError) as err:
        fit_recording(bad)
    assert err.value.row == 700 and err.value.column == "time"


def test_cli_writes_json_and_plot(tmp_path, rate_deg_h):
    import fogbayes.cli.allan  # noqa: F401  (registers the command)
    from fogbayes.cli import main

    rec = _recording(rate_deg_h, "deg/s")
    path = tmp_path / "gyro.csv"
    save(rec, path)
    out, png = tmp_path / "av.json", tmp_path / "av.png"
    code = main(["--quiet", "allan", str(path), "--output-unit", "deg/s", "--taus", "dense",
                 "--per-decade", "5", "--json", str(out), "--plot", str(png)])
    assert code == 0
    doc = json.loads(out.read_text())
    assert doc["taus"] == "dense" and len(doc["tau"]) > 14
    assert doc["fit"]["method"] == "wls" and set(doc["fit"]["terms"]) == set("QNBKR")
    assert png.stat().st_size > 10_000
    assert main(["--quiet", "allan", str(path), "--taus", "weekly", "--json", str(out)]) == 2


def test_posterior_document(rate_deg_h, doc_deg_h):
    doc = fit_recording(_recording(rate_deg_h), bayes=True, seed=1, select=False,
                        num_warmup=200, num_samples=200)
    fit = doc["fit"]
    assert fit["method"] == "bayes"
    for key in ("band", "predictive", "diagnostics"):
        assert key in fit
    band = fit["band"]
    assert np.all(np.asarray(band["adev_low"]) <= band["adev_median"])
    assert np.all(np.asarray(band["adev_median"]) <= band["adev_high"])
    # N is determined by ~1e4 independent samples: posterior and GLS agree within 2 %
    assert fit["terms"]["N"]["value"] == pytest.approx(doc_deg_h["fit"]["terms"]["N"]["value"],
                                                       rel=0.02)
    assert fit["diagnostics"]["divergences"] < 10


def test_constant_output_is_bad_input_not_a_crash(tmp_path):
    """A stuck sensor: every Allan variance is zero; one line naming the file, exit 2."""
    import subprocess
    import sys

    from fogbayes.data import Recording, save

    path = tmp_path / "stuck.csv"
    save(Recording(time=np.arange(3000) / 10.0, output=np.full(3000, 3.0), unit="deg/h"), path)
    r = subprocess.run([sys.executable, "-m", "fogbayes", "-q", "allan", str(path), "--json",
                        str(tmp_path / "a.json")], capture_output=True, text=True)
    assert r.returncode == 2 and "Traceback" not in r.stderr
    err = r.stderr.strip()
    assert err.count("\n") == 0 and "stuck.csv" in err and "output is constant" in err
    assert not (tmp_path / "a.json").exists()
