"""The README tour: the loop on ``fogbayes demo``'s own record finds what the demo planted.

``fogbayes demo --duration 3600 --fs 1`` simulates a chamber test whose bias is the
thermal scenario's quadratic in T (the ``bias-t`` base model's own terms) plus a Shupe term
k dT/dt. ``fogbayes loop REC -m bias-t`` on the written CSV must add exactly the effects
planted beyond the base: read from the simulator's truth (captured from the demo's own
``simulate`` call), not written into the test. An extra effect here would be a false effect
made by our own parts (a loop covariate that differs from the one the truth was made with).
"""

from __future__ import annotations

import json

import numpy as np

import fogbayes.simulate
from fogbayes.cli import main
from fogbayes.loop.bases import parse_orders


def planted_beyond_base(effects: dict, t_order: int) -> list[str]:
    """Names of planted effects a ``bias-t`` base of T order ``t_order`` does not contain:
    a ``temperature_order`` polynomial of degree <= t_order is the base itself."""
    out = []
    for name, p in effects.items():
        if name == "temperature_order" and \
                np.trim_zeros(np.asarray(p["coeffs"], float), "b").size - 1 <= t_order:
            continue
        out.append(name)
    return sorted(out)


def test_loop_on_the_tour_record_adds_only_the_planted_effect(tmp_path, monkeypatch):
    truths = []
    real = fogbayes.simulate.simulate

    def capture(*args, **kwargs):  # the demo's own simulation, as it is called
        sim = real(*args, **kwargs)
        truths.append(sim.truth)
        return sim

    monkeypatch.setattr(fogbayes.simulate, "simulate", capture)
    demo = tmp_path / "demo_out"
    assert main(["--quiet", "demo", "--out", str(demo), "--duration", "3600", "--fs", "1"]) == 0
    assert len(truths) == 1
    want = planted_beyond_base(truths[0].params["effects"], parse_orders("bias-t", None)[0])
    assert want  # the demo plants something beyond the base, else this test says nothing

    doc = tmp_path / "l.json"
    assert main(["--quiet", "loop", str(demo / "demo_recording.csv"), "-m", "bias-t",
                 "--json", str(doc), "--compensated", str(tmp_path / "c.csv")]) == 0
    added = [s["effect"] for s in json.loads(doc.read_text())["steps"]]
    assert sorted(added) == want, f"loop added {added}, the demo planted {want}"


def test_loop_on_the_default_demo_record_adds_only_the_rate_effect():
    """``fogbayes demo`` alone (6.3 h at 10 Hz, seed 0): the record ``run_demo`` simulates
    (``simulate("thermal", seed=0, effects={"temperature_rate": {}})``, its defaults)
    gains ``temperature_rate`` and nothing else. With the simulator's flicker periodic over
    the record, its fundamental (a sine of period T) followed the heat-then-cool programme
    as a hysteresis loop and the loop added ``thermal_hysteresis`` (0.093 deg/h); seeds 1-3
    of the same call were measured clean as well."""
    from fogbayes.loop import run_loop

    sim = fogbayes.simulate.simulate("thermal", seed=0, effects={"temperature_rate": {}})
    want = planted_beyond_base(sim.truth.params["effects"], parse_orders("bias-t", None)[0])
    assert want == ["temperature_rate"]
    res = run_loop(sim.recording, "bias-t")
    assert sorted(s.effect for s in res.steps if s.term is not None) == want, res.effects
