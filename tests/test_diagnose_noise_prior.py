"""Noise prior (``--noise-prior``): the walk cap's units, the caps on every fit, bad files."""

from __future__ import annotations

import json
import math

import pytest

import fogbayes.cli as cli
import fogbayes.cli.loop  # noqa: F401  (registers the command)
from fogbayes.support.jsonable import to_jsonable
from fogbayes.data import save
from fogbayes.loop.context import make_context
from fogbayes.loop.fitting import fit_terms
from fogbayes.loop.noise_prior import (
    GM_PEAK,
    GM_PEAK_TAU,
    NoisePrior,
    prior_from_doc,
    read_noise_prior,
)
from fogbayes.errors import FogbayesError
from fogbayes.inference.noise_ssm import LOG_BOUNDS, make_spec, unpack
from fogbayes.loop import run_loop
from fogbayes.loop.bases import base_terms
from fogbayes.loop.testbed import make_record
from fogbayes.simulate import simulate
from fogbayes.allan.workflow import fit_recording


def test_walk_cap_is_the_walk_the_noise_model_fits():
    """K_max -> log(K^2 dt / 3600 / s2) is in the noise model's own units: on white + walk
    noise of known K the ML walk of the block means scatters around the cap computed from the
    true K. Measured on seeds 0-7 of this set-up (4 h at 2 Hz, 6 s blocks): fitted - cap from
    -0.68 to +0.27, mean -0.12, sd 0.35; the mean of 8 is held to 0.35 (2.8 standard errors),
    each to 1.0. A white level wrong by 2x would shift every value by log 4 = 1.39."""
    diffs = []
    for seed in range(8):
        rec = simulate("static", seed=seed, fs=2.0, duration=4 * 3600.0,
                       noise={"N": 0.003, "K": 0.05}).recording
        ctx = make_context(rec, flicker=False)
        fit = fit_terms(ctx, base_terms(ctx, "allan"))
        fitted = float(unpack(fit.noise.spec, fit.noise.theta).log_rw)
        diffs.append(fitted - NoisePrior(0.05).log_rw_cap(ctx.grid.dt, fit.noise.sigma2))
    assert abs(sum(diffs) / len(diffs)) < 0.35
    assert max(abs(d) for d in diffs) < 1.0


def test_an_allan_document_caps_walk_and_markov_component():
    sim = simulate("static", seed=3, fs=10.0, duration=3600.0, noise={"N": 0.005, "B": 0.02, "K": 0.02})
    doc = json.loads(json.dumps(to_jsonable(fit_recording(sim.recording, model="allan"))))
    p = prior_from_doc(doc, source="static.json")
    assert p.k_max == doc["fit"]["terms"]["K"]["high"]
    sigma_max, tau_max = p.markov_caps(4.0)
    # the white noise's ADEV at tau >= 0.95 dt bounds sigma; the longest tau bounds tau_c
    seen = [h for t, h in zip(doc["tau"], doc["adev_high"]) if t >= 0.945 * 4.0]
    assert sigma_max == pytest.approx(max(seen) / GM_PEAK)
    assert tau_max == pytest.approx(max(doc["tau"]) / GM_PEAK_TAU)
    spec = p.capped(make_spec(4.0, 3 * 3600.0), sigma2=0.02)
    assert spec.tau_max == pytest.approx(tau_max)
    assert spec.log_mvar_max == pytest.approx(math.log(sigma_max ** 2 / 0.02))
    assert spec.log_rw_max == pytest.approx(math.log(p.k_max ** 2 * 4.0 / 3600.0 / 0.02))
    # a datasheet K caps the walk only
    bare = prior_from_doc({"K": 0.02})
    assert bare.markov_caps(4.0) == (None, None)
    assert bare.capped(make_spec(4.0, 3600.0), 0.02).log_mvar_max == LOG_BOUNDS["mvar"][1]


@pytest.mark.parametrize("doc, column", [({"fit": {}}, "K"), ({"K": -1.0}, "K"),
                                         ({"K": "x"}, "K"),
                                         ({"fit": {"terms": {"K": {"high": 0.1}}}}, "adev_high")])
def test_a_bad_prior_names_the_file_and_the_key(doc, column):
    with pytest.raises(FogbayesError) as e:
        prior_from_doc(doc, source="prior.json")
    assert e.value.file == "prior.json" and e.value.column == column
    assert "fogbayes allan" in str(e.value)


def test_a_missing_or_broken_prior_file_is_exit_code_2(tmp_path, capsys):
    rec = make_record(None, seed=0, duration=600.0, fs=1.0).recording
    save(rec, tmp_path / "r.csv")
    (tmp_path / "broken.json").write_text("{K: 0.02")
    for name in ("missing.json", "broken.json"):
        rc = cli.main(["loop", str(tmp_path / "r.csv"), "--model", "bias-t", "--json", "-",
                       "--compensated", str(tmp_path / "c.csv"), "--noise-prior",
                       str(tmp_path / name)])
        assert rc == 2
        err = capsys.readouterr().err
        assert name in err and "Traceback" not in err
    with pytest.raises(FogbayesError, match="does not exist"):
        read_noise_prior(tmp_path / "missing.json")


def test_every_fit_of_the_loop_stays_under_the_cap(tmp_path):
    """A record whose walk (K 0.2) is far above a prior's K_max 0.002: the walk sits at the
    cap in the final fit, the scans say the prior does not fit the record, and the JSON
    carries the prior. (The loop then adds a `time_drift` standing in for the walk: a wrong
    prior is a wrong model, which is why the scans flag it.)"""
    rec = make_record(None, seed=4, duration=2 * 3600.0, fs=1.0,
                      noise={"N": 0.003, "K": 0.2}).recording
    res = run_loop(rec, "bias-t", max_steps=1, noise_prior=NoisePrior(0.002, source="sheet"))
    spec = res.fit.noise.spec
    assert spec.log_rw_max < LOG_BOUNDS["rw"][1] - 5
    for fit in [res.initial_fit, res.fit] + [s.fit for s in res.steps]:
        assert float(unpack(fit.noise.spec, fit.noise.theta).log_rw) <= spec.log_rw_max + 1e-9
    at = [u for u in res.unexplained if u["kind"] == "noise_model_at_bound"]
    assert at and at[0]["detail"]["bound"] == "noise prior"
    doc = res.to_json()
    assert doc["noise_prior"]["K_max_deg_h15"] == 0.002
    assert doc["noise_prior"]["source"] == "sheet"


def test_the_cli_runs_under_a_prior_and_says_so(tmp_path, capsys):
    rec = make_record(None, seed=0, duration=1200.0, fs=1.0).recording
    save(rec, tmp_path / "r.csv")
    (tmp_path / "sheet.json").write_text('{"K": 0.03}')
    rc = cli.main(["loop", str(tmp_path / "r.csv"), "--model", "bias-t", "--max-steps", "0",
                   "--json", str(tmp_path / "l.json"), "--compensated", str(tmp_path / "c.csv"),
                   "--noise-prior", str(tmp_path / "sheet.json")])
    assert rc == 0
    doc = json.loads((tmp_path / "l.json").read_text())
    assert doc["noise_prior"]["K_max_deg_h15"] == 0.03
    assert doc["noise_prior"]["markov_sigma_max_deg_h"] is None
    assert "K <= 0.03" in capsys.readouterr().err
