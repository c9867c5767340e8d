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
