"""An effect defined only in this file flows through the whole package: the simulator plants
it (its closed form), the loop finds it, ``fogbayes loop --max-steps 0 --effect NAME`` fits it
declared, ``fogbayes compensate`` with that document removes it, and the report names it.

The effect: b = k (T - T_ref) dT/dt on the existing ``t_rate`` column kind, with T_ref the
searched parameter (a 1 deg C grid over the record's temperatures). Records: 1 h at 1 Hz of the
``thermal`` scenario (its own noise: N 0.005 deg/sqrt(h), B 0.02 deg/h, K 0.02 deg/h^1.5).
"""

from __future__ import annotations

import json

import numpy as np
import pytest

import fogbayes
import fogbayes.cli as cli
from fogbayes import effects
from fogbayes.data import save
from fogbayes.effects import Candidate, Effect
from fogbayes.effects.base import count
from fogbayes.effects.terms import Term
from fogbayes.loop import run_loop
from fogbayes.loop.testbed import make_record
from fogbayes.simulate import EFFECTS as SIM_EFFECTS
from fogbayes.simulate import simulate

#: planted at this many times its default: 0.04 deg/h per deg C per deg C/min, 2.2 deg/h RMS
MAGNITUDE = 10.0


class ThermalCross(Effect):
    """b = k (T - T_ref) dT/dt (deg/h): a test-only effect; the loop searches T_ref."""

    name = "test_thermal_cross"
    description = "cross term k (T - T_ref) dT/dt, T_ref searched (deg/h per deg C per deg C/min)"
    defaults = {"coeff": 0.004, "T_ref": 20.0}
    size_keys = ("coeff",)

    def plant(self, p):
        return [(Term("t_rate", {"channel": 0, "centre": p["T_ref"], "scale": 1.0,
                                 "rate_scale": 1.0}), [p["coeff"]])]

    def candidates(self, ctx, terms):
        if count(terms, self.name) >= self.max_times:
            return []
        T = ctx.cov.T[:, 0]
        scale = max(float(np.ptp(T)), 1e-3)
        refs = np.arange(np.floor(T.min()), np.ceil(T.max()) + 1.0)  # deg C
        return [Candidate(self.name, "linear", tuple(
            Term("t_rate", {"effect": self.name, "channel": 0, "centre": float(c),
                            "scale": scale, "rate_scale": 1.0}) for c in refs),
            ("temperature", "dT/dt"), "T_ref")]


NAME = ThermalCross.name


@pytest.fixture(scope="module")
def registered():
    effects.register(ThermalCross)
    try:
        yield effects.REGISTRY[NAME]
    finally:
        effects.unregister(NAME)


@pytest.fixture(scope="module")
def record(registered):
    return make_record(NAME, seed=4, duration=3600.0, fs=1.0, magnitude=MAGNITUDE)


@pytest.fixture(scope="module")
def declared(record, tmp_path_factory):
    """``fogbayes loop REC -m bias-t --max-steps 0 --effect NAME`` (in this process, where the
    effect is registered): the document and the report."""
    d = tmp_path_factory.mktemp("declared")
    save(record.recording, d / "rec.csv")
    rc = cli.main(["-q", "loop", str(d / "rec.csv"), "-m", "bias-t", "--max-steps", "0",
                   "--effect", NAME, "--seed", "0", "--json", str(d / "fit.json"),
                   "--report", str(d / "fit.html")])
    assert rc == 0
    return d


def test_the_simulator_plants_its_closed_form(registered):
    assert NAME in SIM_EFFECTS
    sim = simulate("thermal", seed=3, duration=3600.0, fs=1.0, effects={NAME: {"coeff": 0.01}})
    c = sim.truth.covariates
    want = 0.01 * (c.temperature - 20.0) * c.dTdt
    assert np.ptp(want) > 0.1
    np.testing.assert_allclose(sim.truth.effects[NAME], want, rtol=0, atol=1e-12 * np.ptp(want))
    assert sim.truth.params["effects"][NAME] == {"coeff": 0.01, "T_ref": 20.0}


def test_the_loop_finds_it_first(record):
    """Planted at 10x its default, the effect registered at runtime is the loop's first step
    (run_loop's default effect list reads the registry when it runs), at the true T_ref."""
    assert record.effect_params == pytest.approx({"coeff": MAGNITUDE * 0.004, "T_ref": 20.0})
    res = run_loop(record.recording, "bias-t", max_steps=1, n_sims=50, n_refit=1)
    assert res.effects == [NAME]
    assert res.steps[0].term.params["centre"] == 20.0  # the grid point at the truth


def _coefficient(step: dict) -> tuple[float, float]:
    """k and its standard error (deg/h per deg C per deg C/min) from the step's scaled column
    (T - centre) / scale x dT/dt / rate_scale."""
    b = step["detail"]["coefficients_scaled"]["T' (dT/dt)'"]
    s = step["detail"]["scaling"]
    f = 1.0 / (s["scale"] * s["rate_scale"])
    return b["value"] * f, b["stderr"] * f


def test_a_declared_effect_is_fitted_as_a_step(declared, record):
    doc = json.loads((declared / "fit.json").read_text())
    assert [s["effect"] for s in doc["steps"]] == [NAME]
    step = doc["steps"][0]
    assert step["evidence"]["declared"] is True
    assert step["evidence"]["likelihood_ratio"] > 100  # the record says it is there
    assert step["detail"]["scaling"]["centre"] == 20.0  # searched T_ref: the true one
    k, se = _coefficient(step)
    assert 0 < se < 0.01 * MAGNITUDE * 0.004
    assert abs(k - record.effect_params["coeff"]) < 3 * se
    assert step["rms_after"] < 0.1 * step["rms_before"]
    assert any(t["effect"] == NAME for t in doc["calibration"]["terms"])


def test_compensating_with_the_document_removes_it(declared, record, tmp_path):
    """Against the simulation truth, mean kept: a perfect calibration leaves the true noise
    less its time average (IEEE 952: the constant is the run's average output less the
    modelled terms), so the compensated output minus that is what the calibration gets
    wrong of the deterministic bias (planted effect and the scenario's temperature law),
    its constant included.

    Its RMS is bounded by 5 % of the planted effect's (2.2 deg/h, so 0.11 deg/h): what the
    fit cannot know is its bias curve's standard error under the document's covariance,
    sqrt(mean_t x_t' C x_t) = 0.035 deg/h here (intercept included), a third of the bound;
    the coefficient's own standard error is 0.3 % of the effect. The base model alone leaves
    more than half of the effect (all of it, here), so the bound tells a calibration with the
    effect from one without it."""
    out = tmp_path / "comp.csv"
    rc = cli.main(["-q", "compensate", str(declared / "rec.csv"), "--params",
                   str(declared / "fit.json"), "-o", str(out)])
    assert rc == 0
    doc = json.loads((declared / "fit.json").read_text())
    api = fogbayes.compensate(record.recording, doc)["output"]
    cli_out = np.genfromtxt(out, delimiter=",", names=True)["output"]
    np.testing.assert_allclose(cli_out, api, rtol=0, atol=1e-9)

    planted = record.effects[NAME]
    size = np.std(planted)

    ideal = record.noise - np.mean(record.noise)

    def left(output):
        return np.sqrt(np.mean((output - ideal) ** 2))

    assert left(api) < 0.05 * size
    base = run_loop(record.recording, "bias-t", max_steps=0, n_sims=50).to_json()
    assert left(fogbayes.compensate(record.recording, base)["output"]) > 0.5 * size


def test_the_report_names_it(declared):
    html = (declared / "fit.html").read_text()
    assert f"Step 1: declared {NAME}" in html
    assert ThermalCross.description in html


def test_an_unknown_declared_effect_is_one_line(declared, capsys):
    rc = cli.main(["-q", "loop", str(declared / "rec.csv"), "-m", "bias-t", "--max-steps",
                   "0", "--effect", "no_such_effect", "--json", str(declared / "x.json")])
    err = capsys.readouterr().err.strip()
    assert rc == 2 and len(err.splitlines()) == 1 and "Traceback" not in err
    assert "'--effect'" in err and "no_such_effect" in err and NAME in err
    assert "temperature_rate" in err and "markov_noise" not in err
    assert not (declared / "x.json").exists()
    with pytest.raises(fogbayes.errors.FogbayesError, match="argument 'declared'"):
        run_loop(None, "bias-t", declared=("no_such_effect",))
