"""The effect registry (fogbayes.effects): DESIGN.md's names, candidates on chamber and
rate-table records, and an effect registered at runtime reaches the loop's candidates and
leaves again (each plant against its closed form: tests/test_effect_terms.py; the test-only
effect's way through simulate, loop, a declared fit, compensate and report:
tests/test_new_effect.py)."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from fogbayes import effects
from fogbayes.loop.candidates import EFFECTS, MAX_TIMES, candidates_for
from fogbayes.loop.context import make_context
from fogbayes.effects.terms import Term, columns
from fogbayes.effects import Effect
from fogbayes.loop.bases import allowed, base_terms
from fogbayes.loop.testbed import make_record
from fogbayes.simulate import EFFECTS as SIM_EFFECTS
from fogbayes.simulate._checks import SimulationParameterError
from fogbayes.simulate.registry import resolve
from fogbayes.simulate.truth import Covariates
from test_new_effect import ThermalCross

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


@pytest.fixture
def registered():
    effects.register(ThermalCross)
    try:
        yield effects.REGISTRY[ThermalCross.name]
    finally:
        effects.unregister(ThermalCross.name)


def test_an_effect_registered_at_runtime_reaches_the_candidates(contexts, registered):
    name = registered.name
    ctx = contexts["thermal"]
    base = base_terms(ctx, "bias-t")
    found = [c for c in candidates_for(ctx, base) if c.effect == name]
    assert len(found) == 1 and found[0].grid[0].kind == "t_rate"
    assert [c.effect for c in candidates_for(ctx, base, effects=(name,))] == [name]
    assert name in allowed("bias-t")  # the loop's default effect list reads the registry
    assert candidates_for(ctx, base)[-1].effect == "periodic"  # spectral ones stay last


def test_an_unregistered_effect_is_gone_again():
    assert ThermalCross.name not in effects.REGISTRY
    cov = Covariates(np.arange(3.0), np.zeros(3), np.zeros((3, 1)), np.zeros(3), None, None,
                     None)
    with pytest.raises(SimulationParameterError, match="unknown effect"):
        resolve(ThermalCross.name, None, cov)
    with pytest.raises(ValueError, match="already registered"):
        effects.register(effects.REGISTRY["step"])
