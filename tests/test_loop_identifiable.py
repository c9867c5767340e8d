"""The loop warns when temperature and time move together (a law in T and a drift in t
cannot be told apart), and stays quiet on a heating-and-cooling test."""

from __future__ import annotations

import numpy as np

from fogbayes.data import Recording
from fogbayes.loop.context import make_context
from fogbayes.loop.identifiable import R_WARN, collinearity_warnings
from fogbayes.simulate import simulate


def test_a_single_cooling_warns_and_names_the_channel():
    t = np.arange(0.0, 7200.0, 1.0)
    x = t / t[-1]
    T = 20.0 - 40.0 * x + 6.0 * x ** 2  # one slowing cooling, as a TVAC cold test
    rng = np.random.default_rng(0)
    rec = Recording(time=t, output=rng.normal(size=t.size), unit="deg/h",
                    temperatures=(T + 0.01 * rng.normal(size=t.size))[:, None],
                    temperature_names=("gyro_temp",))
    r = np.corrcoef(T, t)[0, 1]
    assert abs(r) >= R_WARN  # the construction is what the rule is about
    w = collinearity_warnings(make_context(rec))
    assert len(w) == 1 and "gyro_temp" in w[0] and "r = -0.99" in w[0]  # block means: -0.9990


def test_a_heating_and_cooling_test_does_not_warn():
    rec = simulate("thermal", seed=0, duration=3600.0, fs=1.0).recording
    assert collinearity_warnings(make_context(rec)) == []
