"""The chamber planner (fogbayes/plan/programme.py, `fogbayes plan-chamber`).

The simulation check of its predictions (the loop's right-first before and after the planned
programme) is benchmarks/bench_plan_chamber.py; here: the statistics against independent
computations, the simulator's programme option, and the command's contract.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from fogbayes.cli import main
from fogbayes.plan.programme import cycling, duel_power, noncentrality
from fogbayes.simulate.profiles import (Ramp, Soak, as_segments, segments_json,
                                        thermal_profile)
from fogbayes.simulate.scenarios import simulate


def test_noncentrality_is_the_residual_of_the_closest_rival_member():
    rng = np.random.default_rng(0)
    mu, rival = rng.normal(size=50), rng.normal(size=(50, 4))
    ref = min(float(np.sum((mu - rival[:, [j]] @ np.linalg.lstsq(rival[:, [j]], mu,
                                                                  rcond=None)[0]) ** 2))
              for j in range(4))
    assert noncentrality(mu, rival) == pytest.approx(ref, rel=1e-10)


def _full_space_power(mu, own, rival, draws, boot, seed):
    """The duel's rejection rate in the full n-dimensional space (no reduction): an
    independent, slower implementation of the definition in the module doc."""
    rng = np.random.default_rng(seed)
    ua = own / np.linalg.norm(own, axis=0)
    ub = rival / np.linalg.norm(rival, axis=0)
    stat = lambda z: ((z @ ua) ** 2).max(-1) - ((z @ ub) ** 2).max(-1)
    rej = 0
    for _ in range(draws):
        z = mu + rng.normal(size=mu.size)
        d = stat(z)
        pb = z @ ub
        j = np.argmax(pb ** 2)
        zs = pb[j] * ub[:, j] + rng.normal(size=(boot, mu.size))
        rej += np.mean(stat(zs) >= d) < 0.05
    return rej / draws


def test_duel_power_matches_the_full_space_definition():
    rng = np.random.default_rng(1)
    n = 120
    rival = rng.normal(size=(n, 3))
    own = 0.7 * rival[:, :1] + rng.normal(size=(n, 2))  # correlated with the rival
    mu = 0.2 * own[:, 0]
    lam = noncentrality(mu, rival)
    fast = duel_power(mu, own, rival, draws=1500, boot=400, seed=2)
    slow = _full_space_power(mu, own, rival, 1500, 400, seed=3)
    assert 0.2 < fast < 0.9, (fast, lam)  # a case where the power is not saturated
    # two Monte Carlo estimates of one probability: binomial sd <= 0.013 each
    assert abs(fast - slow) < 0.05, (fast, slow)


def test_a_rival_that_contains_the_truth_is_never_rejected():
    rng = np.random.default_rng(4)
    rival = rng.normal(size=(80, 2))
    mu = 3.0 * rival[:, 1]
    assert noncentrality(mu, rival) == pytest.approx(0.0, abs=1e-9)
    assert duel_power(mu, mu[:, None], rival, draws=300, boot=200) <= 0.05


def test_a_programme_round_trips_through_json_and_drives_the_simulator():
    segs = cycling(5.0, 600.0, duration=3600.0, low=0.0, high=40.0)
    assert isinstance(segs[0], Soak) and isinstance(segs[1], Ramp)
    assert as_segments(segments_json(segs)) == segs
    sim = simulate("thermal", seed=0, fs=1.0, duration=3600.0, segments=segments_json(segs),
                   noise={})
    ref = thermal_profile(segs, fs=1.0, start=20.0, duration=3600.0)
    T = sim.recording.temperature
    np.testing.assert_allclose(T[:, 0] if T.ndim == 2 else T, ref.temperatures[:, 0],
                               atol=1e-9)
    with pytest.raises(Exception, match="segment 0"):
        as_segments([{"hold": 20}])


def test_plan_chamber_command(tmp_path):
    out = tmp_path / "plan.json"
    base = tmp_path / "mine.json"
    base.write_text(json.dumps([{"soak": 20, "duration": 600}, {"ramp": 60, "rate": 1},
                                {"soak": 60, "duration": 3000}]))
    assert main(["plan-chamber", "--noise", "0.005,0.02,0.02", "--hours", "1", "--fs", "1",
                 "--programme", str(base), "--json", str(out)]) == 0
    doc = json.loads(out.read_text())
    assert doc["schema"] == "fogbayes.plan_chamber/1"
    assert doc["baseline"]["name"] == "your programme"
    worst = min(doc["best"]["noncentrality"].values())
    assert worst == pytest.approx(max(c["worst_noncentrality"] for c in doc["candidates"]))
    assert doc["best"]["name"].startswith("cycle")
    assert all(0.0 <= p <= 1.0 for p in doc["best"]["power"].values())
    assert max(g.get("rate", 0) for g in doc["best"]["segments"]) <= 5.0


@pytest.mark.parametrize("args, flag", [
    (["--hours", "1"], "--noise"),
    (["--noise", "0.005,0.02"], "--noise"),
    (["--noise", "0.005,0.02,0.02", "--lags", "900,300"], "--lags"),
    (["--noise", "0.005,0.02,0.02", "--max-rate", "0"], "--max-rate"),
    (["--noise", "0.005,0.02,0.02", "--low", "30"], "--low"),
])
def test_plan_chamber_refuses_bad_arguments(args, flag, capsys):
    assert main(["plan-chamber", *args]) == 2
    err = capsys.readouterr().err
    assert flag in err and "Traceback" not in err


def test_the_loop_points_an_undecided_thermal_duel_to_the_planner():
    from types import SimpleNamespace as NS

    from fogbayes.cli.loop import undecided
    from fogbayes.loop.ranking import separable_by_programme

    def alt(chosen, other):  # as the loop writes an undecided duel (loop.ranking.alternatives)
        return {"effect": other, "separable_by_programme": separable_by_programme(chosen, other)}

    lag = NS(effect="temperature_gradient",
             evidence={"alternatives": [alt("temperature_gradient", "thermal_lag")]})
    step = NS(effect="step", evidence={"alternatives": [alt("step", "time_drift")]})
    plain = NS(effect="periodic", evidence={})
    lines = undecided([lag, step, plain])
    assert len(lines) == 2
    assert "thermal_lag" in lines[0] and "plan-chamber" in lines[0]
    assert "time_drift" in lines[1] and "plan-chamber" not in lines[1]


def test_the_pairs_are_read_from_the_registry():
    """A lag and a Shupe term each against the other effects a programme separates (docs/plan.md:
    a lag against the gradient and the Shupe term, the Shupe term against both); an effect
    registered as separable becomes everyone's rival, and leaves with its registration."""
    from fogbayes import effects
    from fogbayes.effects.temperature_gradient import TemperatureGradient
    from fogbayes.plan.programme import Pair, pairs_for

    truths = {"thermal_lag": (0.01, [1200.0, 1800.0]), "temperature_rate": (0.3, [None])}
    assert pairs_for(truths) == [
        Pair("thermal_lag", "temperature_gradient", 0.01, 1200.0),
        Pair("thermal_lag", "temperature_gradient", 0.01, 1800.0),
        Pair("thermal_lag", "temperature_rate", 0.01, 1200.0),
        Pair("thermal_lag", "temperature_rate", 0.01, 1800.0),
        Pair("temperature_rate", "thermal_lag", 0.3, None),
        Pair("temperature_rate", "temperature_gradient", 0.3, None)]

    class Crosstalk(TemperatureGradient):
        name = "test_crosstalk"

    effects.register(Crosstalk)
    try:
        rivals = {p.rival for p in pairs_for(truths)}
        assert rivals == {"temperature_gradient", "temperature_rate", "thermal_lag",
                          "test_crosstalk"}
    finally:
        effects.unregister("test_crosstalk")
    assert "test_crosstalk" not in {p.rival for p in pairs_for(truths)}
