"""The thermal model on simulated paper-004 verification runs (truth known).

Runs: fogbayes.simulate "paper004" (room, -40, +60, room; 2 h soaks, 0.5 deg C/min ramps,
1 Hz, order-2 bias in T plus a Shupe term 4 (deg/h)/(deg C/min)), with the thermometer
quantised like the paper's TMP461 (0.0625 deg C). The oracle compensates with the true
deterministic bias, so its bias stability is what noise alone leaves.

Measured (seeds 0-1, three noise levels, see benchmarks/RESULTS_thermal.md for more):
thermal/oracle 0.985-1.001 (default processing), 0.991-1.025 (paper processing);
bias-t/oracle 1.50-2.94. Paper processing at the simulator's paper noise: Bs 1.69 -> 0.50
deg/h, 70 % better (paper: 1.645749 -> 0.501541, 69.53 %).
"""

from __future__ import annotations

import numpy as np
import pytest

from fogbayes.stats.stability import bias_stability, improvement_pct
from fogbayes.simulate import simulate
from fogbayes.thermal.workflow import compensate_recording, fit_recording

TMP461_STEP = 0.0625  # deg C
NOISE = {
    "paper": {"N": 0.008, "B": 0.05},  # the simulator's paper-004 noise (reproduces the paper)
    "markov": {"N": 0.008, "B": 0.05, "markov": {"sigma": 0.3, "tau_c": 300.0}},  # coloured
    "high": {"N": 0.02, "B": 0.15},
}


def _run(seed, noise, **effects):
    sim = simulate("paper004", seed=seed, noise=NOISE[noise], effects=effects or None)
    rec = sim.recording
    rec = rec.replace(temperatures=np.round(rec.temperatures / TMP461_STEP) * TMP461_STEP)
    return rec, rec.rate("deg/h") - sim.truth.error()


def _bs_after(rec, doc):
    return bias_stability(compensate_recording(rec, doc)["output"], rec.time, 1.0)


@pytest.mark.slow
@pytest.mark.parametrize("noise", list(NOISE))
@pytest.mark.parametrize("seed", [0, 1])
def test_thermal_is_within_15_percent_of_the_oracle_and_beats_bias_t(noise, seed):
    rec, oracle = _run(seed, noise)
    bs_oracle = bias_stability(oracle, rec.time, 1.0)
    thermal = _bs_after(rec, fit_recording(rec, model="thermal"))
    bias_t = _bs_after(rec, fit_recording(rec, model="bias-t"))
    assert thermal <= 1.15 * bs_oracle  # measured <= 1.001
    assert bias_t >= 1.3 * thermal  # measured >= 1.50: bias-t cannot see the Shupe term


def test_paper_processing_reproduces_the_papers_figures():
    rec, oracle = _run(0, "paper")
    doc = fit_recording(rec, model="thermal", processing="paper")
    row = doc["metrics"]["full"]["stability"][0]
    assert row["window_s"] == 1.0
    assert row["improvement_pct"] == pytest.approx(improvement_pct(row["before"], row["after"]))
    # the simulator's noise was tuned to the paper, so its figures come back to ~5 %
    assert row["before"] == pytest.approx(1.645749, rel=0.08)  # measured 1.685
    assert row["after"] == pytest.approx(0.501541, rel=0.08)  # measured 0.50
    assert row["improvement_pct"] == pytest.approx(69.53, abs=4.0)  # measured 70.2
    assert row["after"] <= 1.15 * bias_stability(oracle, rec.time, 1.0)
    assert doc["processing"]["rate_method"] == "paper" and doc["outliers"]["method"] == "pauta"
    kinds = {s["kind"] for s in doc["metrics"]["segments"]}
    assert kinds == {"soak", "ramp_up", "ramp_down"}  # per segment, as the paper reports
    # ramps are where the Shupe term acts: they improve (measured 27-46 % on 1 s, 61-74 %
    # on 10 s averages); soaks have nothing to remove (measured -2.5 ... -0.4 % on 1 s:
    # the paper's 10 s differences of a quantised thermometer add a little noise)
    for seg in doc["metrics"]["segments"]:
        one, ten = seg["stability"][0], seg["stability"][1]
        if seg["kind"] == "soak":
            assert abs(one["improvement_pct"]) < 5
        else:
            assert one["improvement_pct"] > 20 and ten["improvement_pct"] > 50


def test_optional_cross_and_gradient_terms_are_needed_when_present():
    # measured: cross term 0.05 -> without/with cross 1.39/1.00 of the oracle;
    # gradient 0.3 deg/h per deg C -> without/with gradient 1.11/1.00
    rec, oracle = _run(5, "paper", paper004={"cross": 0.05})
    bo = bias_stability(oracle, rec.time, 1.0)
    assert _bs_after(rec, fit_recording(rec, model="thermal")) > 1.2 * bo
    assert _bs_after(rec, fit_recording(rec, model="thermal", cross=True)) <= 1.15 * bo
    rec, oracle = _run(5, "paper", temperature_gradient={"coeff": 0.3})
    bo = bias_stability(oracle, rec.time, 1.0)
    assert _bs_after(rec, fit_recording(rec, model="thermal")) > 1.05 * bo
    assert _bs_after(rec, fit_recording(rec, model="thermal", gradient=True)) <= 1.15 * bo


def test_order_selection_by_the_rms_criterion_finds_the_true_orders():
    rec, _ = _run(1, "paper")
    doc = fit_recording(rec, model="thermal", orders="auto")
    sel = doc["order_selection"]
    assert len(sel["candidates"]) == len(sel["scores"]) == 6
    t_order, r_order = sel["best"]
    assert t_order >= 2 and r_order >= 1  # truth: order 2 in T, 1 in dT/dt
    assert doc["params"]["spec"]["t_order"] == t_order
