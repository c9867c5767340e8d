"""The loop report's "against the added term's driver" panel plots the partial residual
(residual after the step + the added term's part). On the README tour's record (a Shupe
term planted on the exact sensor rate), its two cooling ramps, at different temperatures,
fall on one line; the old difference before - after added the refit's shift of the
temperature law and split them into two branches (0.3 deg/h apart), as if hysteresis."""

from __future__ import annotations

import numpy as np

from fogbayes.loop import run_loop
from fogbayes.plot.loop import step_figure
from fogbayes.simulate import simulate


def test_cooling_ramps_fall_on_one_line_in_the_driver_panel():
    sim = simulate("thermal", seed=0, duration=3600.0, fs=1.0, effects={"temperature_rate": {}})
    res = run_loop(sim.recording, "bias-t", max_steps=1)
    assert res.effects == ["temperature_rate"]
    ax = step_figure(res, 0).axes[1]
    (x, partial), (_, own) = [ln.get_xydata().T for ln in ax.get_lines()[:2]]
    # blocks of the panel in time order: which cooling ramp each belongs to
    T = sim.recording.temperatures[:, 0]
    t = sim.recording.time - sim.recording.time[0]
    tb = np.arange(x.size) * 10.0 + 5.0
    Tb = np.interp(tb, t, T)
    cooling = x < -1.0  # deg C/min
    # the term's part is a function of its driver: one line, not two cooling branches
    line = np.polyval(np.polyfit(x, own, 1), x)
    warm, cold = (own - line)[cooling & (Tb > 20.0)], (own - line)[cooling & (Tb < 20.0)]
    assert warm.size > 10 and cold.size > 10
    assert abs(np.mean(warm) - np.mean(cold)) < 0.02  # deg/h; the branches were 0.3 apart
    # and the points scatter about it by the residual, on both ramps alike
    gap = partial - own
    assert abs(np.mean(gap[cooling & (Tb > 20.0)]) - np.mean(gap[cooling & (Tb < 20.0)])) < 0.1
