"""``fogbayes pool -m bias-t``: pooled bias laws of a fleet (fogbayes.pool.thermal).

A fleet of 6 simulated sensors (30 min, 1 Hz chamber tests, the scenario's noise) whose laws
a0 + a1 (T - 20) + a2 (T - 20)^2 are drawn from a known population, and a seventh unit whose
a0 is 40 population sd off. The coverage of the population intervals over 40 fleets is in
benchmarks/RESULTS_pool.md (bench_pool_thermal.py); here: each unit's law is right within
its own standard errors, the outlier alone is flagged, and the population mean of a0 lies
with the population, not with the outlier.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

import fogbayes.cli as cli
from fogbayes.data import save
from fogbayes.pool.thermal import fit_unit
from fogbayes.simulate import simulate

MU = np.array([0.5, 0.01, 2e-4])
SD = np.array([0.02, 5e-4, 2e-5])


def _unit(seed: int, coeffs) -> object:
    return simulate("thermal", seed=seed, duration=1800.0, fs=1.0,
                    effects={"temperature_order": {"coeffs": list(coeffs), "T_ref": 20.0}})


@pytest.fixture(scope="module")
def fleet(tmp_path_factory):
    d = tmp_path_factory.mktemp("pool_thermal")
    rng = np.random.default_rng(3)
    truth = MU + SD * rng.standard_normal((7, 3))
    truth[6, 0] = MU[0] + 40 * SD[0]  # the outlier
    for u, coeffs in enumerate(truth):
        save(_unit(200 + u, coeffs).recording, d / f"unit{u}.csv")
    rc = cli.main(["-q", "pool", str(d), "-m", "bias-t", "--json", str(d / "pool.json")])
    assert rc == 0
    return d, truth, json.loads((d / "pool.json").read_text())


def test_each_unit_law_is_right_within_its_standard_errors(fleet):
    _, truth, doc = fleet
    (pool,) = doc["channels"].values()
    for u, row in enumerate(pool["units"]):
        for j, t in enumerate(pool["terms"]):
            single = row["terms"][t]["single"]
            se = (single["high"] - single["low"]) / (2 * 1.6448536269514722)
            assert abs(single["value"] - truth[u, j]) < 4.5 * se, (u, t)


def test_the_outlier_alone_is_flagged_and_does_not_drag_the_population(fleet):
    _, truth, doc = fleet
    (pool,) = doc["channels"].values()
    assert doc["model"] == "bias-t" and pool["converged"]
    assert pool["flagged"] == ["sim-thermal-206"]  # unit6.csv: its sensor id names it
    a0 = pool["population"]["a0"]["mean"]
    assert abs(a0["value"] - truth[:6, 0].mean()) < abs(a0["value"] - truth[6, 0]) / 5
    assert pool["population"]["a0"]["spread_sd"]["unit"] == "deg/h"


def test_a_soaked_unit_is_refused_by_name():
    rec = simulate("static", seed=1, duration=600.0, fs=1.0).recording
    with pytest.raises(Exception, match="temperature does not vary"):
        fit_unit(rec)


def test_noise_only_options_are_refused_in_one_line(fleet, capsys):
    d, _, _ = fleet
    rc = cli.main(["pool", str(d), "-m", "bias-t", "--report", str(d / "r.html"),
                   "--json", str(d / "x.json")])
    err = capsys.readouterr().err
    assert rc == 2 and err.count("\n") == 1 and not (d / "x.json").exists()
