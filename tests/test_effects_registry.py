"""The effect registry (fogbayes.effects): DESIGN.md's names, candidates on chamber and
rate-table records, and an effect defined only here reaches the loop's candidates and the
simulator (each plant against its closed form: tests/test_effect_terms.py)."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from fogbayes import effects
from fogbayes.diagnose.candidates import EFFECTS, MAX_TIMES, candidates_for
from fogbayes.diagnose.context import make_context
from fogbayes.effects.terms import Term, columns
from fogbayes.effects import Candidate, Effect
from fogbayes.loop.bases import base_terms
from fogbayes.loop.testbed import make_record
from fogbayes.simulate import EFFECTS as SIM_EFFECTS
from fogbayes.simulate import simulate
from fogbayes.simulate._checks import SimulationParameterError
from fogbayes.simulate.registry import resolve
from fogbayes.simulate.truth import Covariates

DESIGN = Path(__file__).resolve().parent.parent / "docs" / "DESIGN.md"
RATE_TABLE = ("scale_factor_nonlinearity", "scale_factor_asymmetry", "scale_factor_temperature")


def _design_names() -> list[str]:
    text = DESIGN.read_text()
    start = text.index("Effect names (the loop must know at least these)")
    end = text.index("is a noise component", start)
    return re.findall(r"`([a-z_]+)`", text[start:end])


def test_the_registry_holds_designs_effect_names_in_its_order():
    names = _design_names()
    assert len(names) == 12 and names[-1] == "markov_noise"
    assert list(effects.REGISTRY) == names
    assert EFFECTS == tuple(names)  # the loop's view
    assert set(SIM_EFFECTS) == set(names) | {"paper004"}  # the simulator's, plus paper 004's law
    assert MAX_TIMES == {n: e.max_times for n, e in effects.REGISTRY.items() if e.max_times > 1}


def _searched(eff: Effect) -> bool:
    return type(eff).candidates is not Effect.candidates


@pytest.fixture(scope="module")
def contexts():
    chamber = make_record(None, seed=11, duration=3 * 3600.0, fs=1.0)
    table = make_record(None, seed=12, duration=3 * 3600.0, fs=1.0, profile="ratetable")
    return {"thermal": make_context(chamber.recording, target_blocks=600),
            "ratetable": make_context(table.recording, target_blocks=600)}


@pytest.mark.parametrize("name", [n for n, e in effects.REGISTRY.items() if _searched(e)])
def test_every_searched_effect_has_candidates_on_its_record(contexts, name):
    ctx = contexts["ratetable" if name in RATE_TABLE else "thermal"]
    base = base_terms(ctx, "bias-t")
    got = effects.REGISTRY[name].candidates(ctx, base)
    assert got and all(c.effect == name for c in got)
    assert [c for c in candidates_for(ctx, base) if c.effect == name] == got
    for c in got:
        for term in c.grid:
            assert term.params["effect"] == name
            col = columns(term, ctx.cov)
            assert np.all(np.isfinite(col)) and np.ptp(col) > 0  # a column that varies


def test_an_effect_added_its_maximum_number_of_times_is_no_longer_a_candidate(contexts):
    ctx = contexts["thermal"]
    base = base_terms(ctx, "bias-t")
    for name in ("step", "periodic", "time_drift"):
        eff = effects.REGISTRY[name]
        had = [Term("step", {"effect": name, "time": 100.0 * (i + 1)})
               for i in range(eff.max_times)]
        assert eff.candidates(ctx, base + had[:-1])
        assert eff.candidates(ctx, base + had) == []


class ThermalCross(Effect):
    """b = k (T - T_ref) dT/dt on the existing t_rate kind: a test-only effect."""

    name = "test_thermal_cross"
    description = "k (T - T_ref) dT/dt (deg/h per deg C per deg C/min)"
    defaults = {"coeff": 0.004, "T_ref": 20.0}
    size_keys = ("coeff",)

    def plant(self, p):
        return [(Term("t_rate", {"channel": 0, "centre": p["T_ref"], "scale": 1.0,
                                 "rate_scale": 1.0}), [p["coeff"]])]

    def candidates(self, ctx, terms):
        if any(t.kind == "t_rate" for t in terms):
            return []
        T = ctx.cov.T[:, 0]
        return [Candidate(self.name, "linear", (Term("t_rate", {
            "effect": self.name, "channel": 0, "centre": float(np.mean(T)),
            "scale": max(float(np.ptp(T)), 1e-3), "rate_scale": 1.0}),),
            ("temperature", "dT/dt"), None)]


@pytest.fixture
def registered():
    effects.register(ThermalCross)
    try:
        yield effects.REGISTRY[ThermalCross.name]
    finally:
        effects.unregister(ThermalCross.name)


def test_an_effect_defined_in_a_test_reaches_the_candidates_and_the_simulator(contexts,
                                                                              registered):
    name = registered.name
    ctx = contexts["thermal"]
    base = base_terms(ctx, "bias-t")
    found = [c for c in candidates_for(ctx, base) if c.effect == name]
    assert len(found) == 1 and found[0].grid[0].kind == "t_rate"
    assert [c.effect for c in candidates_for(ctx, base, effects=(name,))] == [name]
    assert candidates_for(ctx, base)[-1].effect == "periodic"  # spectral ones stay last

    assert name in SIM_EFFECTS
    sim = simulate("thermal", seed=3, duration=3600.0, fs=1.0,
                   effects={name: {"coeff": 0.01}})
    c = sim.truth.covariates
    want = 0.01 * (c.temperature - 20.0) * c.dTdt
    assert np.ptp(want) > 0.1
    np.testing.assert_allclose(sim.truth.effects[name], want, rtol=0, atol=1e-12 * np.ptp(want))
    assert sim.truth.params["effects"][name] == {"coeff": 0.01, "T_ref": 20.0}

    rec = make_record(name, seed=4, duration=3600.0, fs=1.0, magnitude=3.0)
    assert rec.effect_params["coeff"] == pytest.approx(3.0 * 0.004, rel=1e-12)


def test_an_effect_registered_at_runtime_is_found_by_the_loop(registered):
    """run_loop's default effect list reads the registry when it runs: planted at 10x its
    default, the test-only effect is the loop's first step."""
    from fogbayes.loop import run_loop
    from fogbayes.loop.bases import allowed

    assert registered.name in allowed("bias-t")
    rec = make_record(registered.name, seed=4, duration=3600.0, fs=1.0, magnitude=10.0)
    res = run_loop(rec.recording, "bias-t", max_steps=1, n_sims=50, n_refit=1)
    assert res.effects == [registered.name]


def test_an_unregistered_effect_is_gone_again():
    assert ThermalCross.name not in effects.REGISTRY
    cov = Covariates(np.arange(3.0), np.zeros(3), np.zeros((3, 1)), np.zeros(3), None, None,
                     None)
    with pytest.raises(SimulationParameterError, match="unknown effect"):
        resolve(ThermalCross.name, None, cov)
    with pytest.raises(ValueError, match="already registered"):
        effects.register(effects.REGISTRY["step"])
