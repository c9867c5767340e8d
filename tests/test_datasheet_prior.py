"""Priors from a datasheet: units, the log-normal density, its pull on the posterior, the
``fogbayes prior`` / ``allan --prior`` / ``loop --noise-prior`` plumbing, bad documents."""

from __future__ import annotations

import functools
import json
import math

import numpy as np
import pytest
from scipy import stats

import fogbayes.cli as cli
import fogbayes.cli.allan  # noqa: F401  (registers the command)
import fogbayes.cli.loop  # noqa: F401
import fogbayes.cli.prior  # noqa: F401
from fogbayes.data import Metadata, Recording, save
from fogbayes.loop.noise_prior import prior_from_doc, read_noise_prior
from fogbayes.errors import FogbayesError, UnitError
from fogbayes.allan import bayes as ab
from fogbayes.allan.data import prepare
from fogbayes.allan.fit import fit_range
from fogbayes.inference.datasheet import (
    DatasheetPrior,
    TermPrior,
    build_prior,
    convert,
    log_density,
    read_prior,
    validate_prior,
)
from fogbayes.simulate.noise import allan_noise

FS = 10.0
TRUTH = dict(Q=0.19, N=0.01, B=0.165, K=0.66)
#: every posterior here has these sizes and one record length: one compiled sampler
DRAWS = {"num_warmup": 300, "num_samples": 300}


# -- units ----------------------------------------------------------------------------
@pytest.mark.parametrize("quantity, value, unit, expected", [
    ("ARW", 1.0, "deg/sqrt(h)", 1.0),
    ("ARW", 1.0, "deg/h/sqrt(Hz)", 1.0 / 60.0),      # deg/h x sqrt(s) = deg/h x sqrt(h)/60
    ("ARW", 1.0, "°/h/√Hz", 1.0 / 60.0),              # the same, as sheets print it
    ("ARW", 1.0, "deg/hr/rt(Hz)", 1.0 / 60.0),
    ("ARW", 1.0, "deg/s/sqrt(Hz)", 60.0),            # deg/sqrt(s) = 60 deg/sqrt(h)
    ("ARW", 1.0, "rad/s/sqrt(Hz)", 60.0 * 180.0 / math.pi),
    ("ARW", 10.0, "mdps/sqrt(Hz)", 0.6),             # 10 mdeg/s/sqrt(Hz) = 0.01 x 60
    ("bias instability", 1.0, "deg/s", 3600.0 / 0.66428),
    ("RRW", 1.0, "deg/h/sqrt(h)", 1.0),
    ("RRW", 1.0, "deg/h^1.5", 1.0),
    ("RRW", 1.0, "deg/h/sqrt(s)", 60.0),             # 1/sqrt(s) = 60/sqrt(h)
    ("RRW", 1.0, "deg/s/sqrt(s)", 3600.0 * 60.0),
    ("RRW", 1.0, "deg/h^2/sqrt(Hz)", 1.0 / 60.0),
])
def test_units_convert_to_canonical_by_hand_values(quantity, value, unit, expected):
    assert convert(quantity, value, unit) == pytest.approx(expected, rel=2e-5)


def test_bias_instability_is_the_adev_floor_unless_told_otherwise():
    # the ADEV floor of flicker rate noise of coefficient B is sqrt(2 ln2 / pi) B = 0.664 B
    assert convert("bias instability", 0.664, "deg/h") == pytest.approx(1.0, rel=1e-3)
    assert convert("bias instability", 0.664, "deg/h", bias_instability_is="B") == 0.664
    doc = build_prior(bias_instability=0.5).to_doc()
    assert "0.6643" in doc["terms"]["B"]["datasheet"]["convention"]


def test_unknown_units_and_bad_values_are_refused_with_a_fix():
    with pytest.raises(UnitError) as e:
        convert("RRW", 1.0, "deg/furlong", flag="--rrw")
    assert e.value.column == "--rrw-unit" and "deg/h/sqrt(h)" in e.value.fix
    for bad in (0.0, -1.0, float("nan")):
        with pytest.raises(FogbayesError, match="positive"):
            build_prior(arw=bad)
    with pytest.raises(FogbayesError, match="looseness"):
        build_prior(arw=0.1, looseness=1.0)


# -- the prior density -----------------------------------------------------------------
def test_log_normal_prior_is_scipys_with_90_percent_within_the_looseness():
    p = TermPrior(0.3, 3.0)
    ref = stats.lognorm(s=math.log(3.0) / stats.norm.ppf(0.95), scale=0.3)
    theta = np.geomspace(0.01, 10.0, 25)
    np.testing.assert_allclose(log_density(theta, p), ref.logpdf(theta), rtol=1e-12)
    assert ref.cdf(0.3 * 3.0) - ref.cdf(0.3 / 3.0) == pytest.approx(0.90, abs=1e-9)
    # the sampler's prior on log theta: the log-normal's (+ the Jacobian log theta) on the
    # sheet's terms, the half-normal's on the others
    sheet = DatasheetPrior({"K": p})
    loc = np.log([0.2, 0.01, 0.2, 0.5, 1.0])
    logp = np.log([0.15, 0.012, 0.1, 0.7, 0.2])
    got = np.asarray(ab.log_prior(logp, loc, ab.sheet_args(sheet)))
    assert got[3] == pytest.approx(ref.logpdf(0.7) + math.log(0.7), rel=1e-12)
    half = stats.halfnorm(scale=3.0 * np.exp(loc)).logpdf(np.exp(logp)) + logp
    np.testing.assert_allclose(np.delete(got, 3), np.delete(half, 3), rtol=1e-12)


# -- the posterior -------------------------------------------------------------------
@pytest.fixture(scope="module")
def short():
    """Seven minutes at 10 Hz of mix A: K (crossover with B at 300 s) is not resolved."""
    y = allan_noise(4 * 2**12, FS, seed=5, flicker_span=1, **TRUTH)[:2**12]
    return y, fit_range(prepare(y, FS))[0]


def _k_median(data, prior):
    post = ab.fit_bayes(data, ("Q", "N", "B", "K"), seed=0, prior=prior, **DRAWS)
    return post.fit.terms["K"].value, post


def test_a_tight_prior_pins_k_a_loose_one_does_not_and_no_sheet_recompiles(short):
    """Sheet K = 3 deg/h^1.5, within what the 7-minute record allows (its K interval without
    a sheet spans a factor ~9): looseness 1.05 puts the median within 5 % of it; looseness
    100 leaves it to the data (measured: 1.04, a factor 2.9 below the sheet)."""
    _, data = short
    tight, post = _k_median(data, DatasheetPrior({"K": TermPrior(3.0, 1.05)}))
    traces = dict(ab.TRACES)
    loose, _ = _k_median(data, DatasheetPrior({"K": TermPrior(3.0, 100.0)}))
    _k_median(data, None)
    assert abs(math.log(tight / 3.0)) < 0.05
    assert abs(math.log(loose / 3.0)) > math.log(1.5)
    assert ab.TRACES == traces  # another sheet, or none: the same compiled sampler
    assert post.diagnostics["prior"].startswith("datasheet: log-normal on K")


# -- command line ----------------------------------------------------------------------
def _sheet(tmp_path, *extra):
    path = tmp_path / "sheet.json"
    rc = cli.main(["-q", "prior", "--arw", "0.6", "--arw-unit", "deg/h/sqrt(Hz)",
                   "--bias-instability", "0.11", "--looseness", "3", "--sensor", "sim A",
                   "--json", str(path), *extra])
    assert rc == 0
    return path


def test_prior_command_writes_a_document_that_reads_back(tmp_path):
    path = _sheet(tmp_path, "--rrw", "0.02", "--rrw-unit", "deg/h/sqrt(h)")
    doc = json.loads(path.read_text())
    assert doc["schema"] == "fogbayes.prior/1" and doc["sensor"] == "sim A"
    n = doc["terms"]["N"]
    assert n["value"] == pytest.approx(0.01) and n["unit"] == "deg/sqrt(h)"
    assert n["datasheet"] == {"value": 0.6, "unit": "deg/h/sqrt(Hz)", "quantity": "ARW"}
    assert doc["terms"]["B"]["value"] == pytest.approx(0.11 / 0.66428, rel=1e-4)
    sheet = read_prior(path)
    assert set(sheet.terms) == {"N", "B", "K"} and sheet.terms["K"].looseness == 3.0


def test_allan_cli_records_the_prior_and_keeps_its_terms(tmp_path, short, monkeypatch):
    import fogbayes.allan.workflow as wf

    y, _ = short
    rec = Recording(time=np.arange(y.size) / FS, output=y, unit="deg/h",
                    meta=Metadata(sensor_id="sim", sample_rate=FS))
    save(rec, tmp_path / "short.csv")
    path = _sheet(tmp_path, "--rrw", "1.0")
    monkeypatch.setattr(wf, "fit_recording", functools.partial(wf.fit_recording, **DRAWS))
    out = tmp_path / "av.json"
    assert cli.main(["-q", "allan", str(tmp_path / "short.csv"), "--bayes", "--prior",
                     str(path), "--json", str(out)]) == 0
    fit = json.loads(out.read_text())["fit"]
    prior = fit["prior"]
    assert prior["source"] == str(path) and prior["sensor"] == "sim A"
    k = prior["terms"]["K"]
    assert (k["value"], k["looseness"], k["unit"]) == (1.0, 3.0, "deg/h^1.5")
    assert prior["terms"]["N"]["datasheet"]["unit"] == "deg/h/sqrt(Hz)"
    # the sheet's terms are kept by the selection, whatever the short record says about K
    assert {"N", "B", "K"} <= set(fit["selection"]["present"])
    assert "datasheet" in fit["selection"]["rule"]


def test_prior_without_bayes_is_one_line_and_exit_2(tmp_path, capsys):
    path = _sheet(tmp_path)
    capsys.readouterr()
    rc = cli.main(["allan", str(tmp_path / "any.csv"), "--prior", str(path), "--json", "-"])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1 and "'--prior'" in err[0] and "--bayes" in err[0]


@pytest.mark.parametrize("edit, key", [
    (lambda d: d.update(schema="fogbayes.prior/2"), "schema"),
    (lambda d: d.update(schema="fogbayes.fit/1"), "schema"),
    (lambda d: d["terms"]["N"].update(value=-0.01), "terms.N.value"),
    (lambda d: d["terms"]["N"].update(value=0), "terms.N.value"),
    (lambda d: d["terms"]["B"].update(looseness=1.0), "terms.B.looseness"),
    (lambda d: d["terms"]["B"].update(looseness=0.5), "terms.B.looseness"),
    (lambda d: d["terms"]["N"].update(unit="deg/h/sqrt(Hz)"), "terms.N.unit"),
    (lambda d: d["terms"].update(ARW=d["terms"].pop("N")), "terms.ARW"),
    (lambda d: d.update(terms={}), "terms"),
])
def test_a_bad_prior_document_is_one_line_naming_file_and_key(tmp_path, capsys, edit, key):
    doc = json.loads(_sheet(tmp_path).read_text())
    edit(doc)
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(doc))
    capsys.readouterr()
    rc = cli.main(["allan", str(tmp_path / "any.csv"), "--bayes", "--prior", str(bad),
                   "--json", "-"])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1, err
    assert str(bad) in err[0] and f"'{key}'" in err[0] and "Fix:" in err[0]


def test_an_unreadable_prior_is_exit_2(tmp_path, capsys):
    (tmp_path / "broken.json").write_text("{schema: ")
    for name in ("missing.json", "broken.json"):
        rc = cli.main(["allan", str(tmp_path / "any.csv"), "--bayes", "--prior",
                       str(tmp_path / name), "--json", "-"])
        err = capsys.readouterr().err
        assert rc == 2 and name in err and "Traceback" not in err


# -- loop --noise-prior -------------------------------------------------------------
def test_noise_prior_from_a_datasheet_caps_k_at_value_times_looseness(tmp_path):
    path = _sheet(tmp_path, "--rrw", "0.02", "--rrw-unit", "deg/h/sqrt(h)")
    cap = read_noise_prior(path)
    assert cap.k_max == pytest.approx(0.02 * 3.0)
    assert cap.markov_caps(4.0) == (None, None)  # a sheet has no ADEV curve
    assert str(path) in cap.source and "datasheet" in cap.source
    # the same through the document's own numbers: value x looseness, any unit on the sheet
    doc = build_prior(rrw=1.0, rrw_unit="deg/h/sqrt(s)", looseness=2.0).to_doc()
    assert prior_from_doc(doc).k_max == pytest.approx(120.0)


def test_a_sheet_without_rrw_gives_no_walk_cap_and_says_so(tmp_path, capsys):
    path = _sheet(tmp_path)
    with pytest.raises(FogbayesError) as e:
        read_noise_prior(path)
    assert e.value.column == "terms.K" and e.value.file == str(path)
    assert "no rate random walk" in e.value.problem and "--rrw" in e.value.fix
    capsys.readouterr()
    rc = cli.main(["loop", str(tmp_path / "any.csv"), "--model", "bias-t", "--json", "-",
                   "--compensated", str(tmp_path / "c.csv"), "--noise-prior", str(path)])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1 and "terms.K" in err[0]


def test_validate_prior_round_trips_and_refuses_bad_types():
    sheet = build_prior(arw=0.05, rrw=0.1, sensor="x")
    back = validate_prior(json.loads(json.dumps(sheet.to_doc())), "mem")
    assert back.terms["N"].value == 0.05 and back.terms["K"].value == 0.1
    with pytest.raises(FogbayesError) as e:
        validate_prior([1, 2], "mem")
    assert e.value.file == "mem"
    with pytest.raises(FogbayesError, match="looseness"):
        validate_prior({"schema": "fogbayes.prior/1",
                        "terms": {"N": {"value": 0.1, "unit": "deg/sqrt(h)",
                                        "looseness": True}}}, "mem")
