"""Recording-length planning (fogbayes.plan, ``fogbayes plan``): the predicted standard
errors are the GLS fit's, behave as theory says on white noise, and the search returns the
shortest length that meets the target; bad requests are refused in one line."""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy import special

import fogbayes
import fogbayes.cli.plan  # noqa: F401  (registers the command)
from fogbayes.cli import main
from fogbayes.allan.data import prepare, restrict
from fogbayes.allan.fit import fit_wls
from fogbayes.allan.model import TERMS, AllanParams
from fogbayes.plan import (PlanError, expected_data, log_se, plan_from_pilot, plan_length,
                           predicted_se, predicted_width)
from fogbayes.simulate.noise import allan_noise

MIX_A = AllanParams(Q=0.19, N=0.01, B=0.165, K=0.66)  # benchmarks/coverage_allan.py, 10 Hz


def _pilot(n=1 << 14, fs=10.0, seed=3, **p):
    return allan_noise(4 * n, fs, seed=seed, flicker_span=1, **p)[:n]


@pytest.mark.parametrize("terms, drop", [(("Q", "N", "B"), 0), (("Q", "N", "B", "K"), 2)])
def test_se_at_the_pilots_length_is_the_fits(terms, drop):
    # Same formula on the same inputs (tau grid, counts, tensors, parameters, penalty):
    # only floating-point rounding may differ, so 1e-9 relative. ``drop`` leaves out the
    # shortest taus as fit_range does, which the plan follows through tau_min.
    fs = 10.0
    data = prepare(_pilot(fs=fs, **MIX_A._asdict()), fs)
    data = restrict(data, np.arange(data.tau.size) >= drop)
    fit = fit_wls(data, terms)
    assert fit.info["dispersion"] == 1.0  # else the fit scales its se
    pred = predicted_se(fit.params, fs, data.n, terms, tau_min=data.tau[0])
    got = {t: fit.info["se_log"][TERMS.index(t)] for t in terms}
    for t in terms:
        assert pred[t] == pytest.approx(got[t], rel=1e-9)


def test_white_noise_single_tau_closed_form():
    # N alone, only m = 1 kept: the overlapping AVAR at m = 1 of white noise has relative
    # variance (3M - 1) / M^2 (d_i = y_{i+1} - y_i: Var d = 2, Cov(d_i, d_i+1) = -1), plus
    # the EDF floor 2 / (100 M) of model_moments; J = 2, so
    # se = (4 / trigamma(nu / 2) + 1 / 10^2)^-1/2 with nu = 2 / relvar.
    n = 4095
    data = expected_data(AllanParams(N=0.01), 1.0, n)
    one = restrict(data, [0])
    M = n - 1
    nu = 2.0 / ((3 * M - 1) / M**2 + 2.0 / (100 * M))
    want = (4.0 / special.polygamma(1, nu / 2) + 0.01) ** -0.5
    assert log_se(AllanParams(N=0.01), one, ("N",))["N"] == pytest.approx(want, rel=1e-10)


def test_white_noise_se_scales_like_one_over_sqrt_n():
    # Octave GLS on white noise: between the Cramer-Rao bound of the variance of n white
    # samples, se(log N) = 1/sqrt(2n), and the m = 1 estimate alone, sqrt(3/(4n)); and
    # se sqrt(n) constant (each doubling of n adds one octave of little weight).
    p = AllanParams(N=0.01)
    ns = [(1 << k) - 1 for k in (12, 14, 16, 18)]
    se = np.array([predicted_se(p, 1.0, n)["N"] for n in ns])
    assert np.all(se > 1 / np.sqrt(2 * np.array(ns)))
    assert np.all(se < np.sqrt(3 / (4 * np.array(ns))))
    c = se * np.sqrt(ns)
    assert np.ptp(c) / c.mean() < 0.01


def test_width_decreases_with_n():
    ns = np.unique(np.geomspace(1 << 10, 1 << 18, 20).astype(int))
    w = [predicted_width(MIX_A, 10.0, n, "K") for n in ns]
    assert np.all(np.diff(w) < 0)
    assert w[-1] < 0.5 < w[0]


@pytest.mark.parametrize("term, precision", [("N", 0.02), ("B", 0.1)])
def test_plan_from_values_is_the_shortest_that_meets(term, precision):
    plan = plan_length(MIX_A, 10.0, term, precision)
    assert plan.half_width <= precision
    assert predicted_width(MIX_A, 10.0, plan.n, term) <= precision
    assert predicted_width(MIX_A, 10.0, int(0.9 * plan.n), term) > precision
    assert plan.hours == pytest.approx(plan.n / 10.0 / 3600.0)
    assert plan.terms == ("Q", "N", "B", "K") and not plan.at_minimum


def test_plan_from_values_refuses():
    with pytest.raises(PlanError, match="fraction"):
        plan_length(MIX_A, 10.0, "K", 0.0)
    with pytest.raises(PlanError, match="fraction"):
        plan_length(MIX_A, 10.0, "K", 10.0)  # 10 meant as 10 %
    with pytest.raises(PlanError, match="more than 2 days") as err:
        plan_length(MIX_A, 10.0, "K", 0.01, max_days=2)  # needs 4000 h
    assert err.value.fix and "looser" in err.value.fix
    with pytest.raises(PlanError, match="not in the model"):
        plan_length(AllanParams(N=0.01, B=0.1), 10.0, "K", 0.1)
    with pytest.raises(PlanError, match="positive"):
        plan_length(AllanParams(N=0.01, B=-0.1), 10.0, "N", 0.1, terms=("N", "B"))
    assert plan_length(MIX_A, 10.0, "K", 0.01, max_days=2, refuse=False) is None


def test_plan_from_pilot_range_brackets_the_point_plan():
    fs = 10.0
    pp = plan_from_pilot(_pilot(fs=fs, Q=0.19, N=0.01, B=0.165), fs, "N", 0.02)
    assert set(pp.terms) <= {"Q", "N", "B"} and "K" not in pp.terms  # no K in this pilot
    assert pp.range_hours[0] <= pp.plan.hours <= pp.range_hours[1]
    # K is not resolved here, so the long end assumes it at its upper bound (step 5)
    assert set(pp.assumed) == {"K"} and pp.assumed["K"] > 0
    assert pp.range.params_high.K == pytest.approx(pp.assumed["K"], rel=1e-9)
    assert pp.plan.half_width <= 0.02 < pp.pilot_width or pp.plan.at_minimum
    with pytest.raises(PlanError, match="does not resolve K") as err:
        plan_from_pilot(_pilot(fs=fs, Q=0.19, N=0.01, B=0.165), fs, "K", 0.1)
    assert "longer pilot" in err.value.fix


@pytest.fixture(scope="module")
def pilot_file(tmp_path_factory):
    fs, n = 10.0, 1 << 14
    y = _pilot(n=n, fs=fs, Q=0.19, N=0.01, B=0.165)
    path = tmp_path_factory.mktemp("plan") / "pilot.npz"
    fogbayes.save(fogbayes.Recording(time=np.arange(n) / fs, output=y, unit="deg/h"), path)
    return path


def test_cli_plan_prints_and_writes_json(pilot_file, tmp_path, capsys):
    assert main(["plan", str(pilot_file), "--term", "N", "--precision", "0.02"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0].startswith("plan: pilot") and any("record" in ln for ln in out)
    assert any(ln.strip().startswith("range") for ln in out)
    js = tmp_path / "plan.json"
    assert main(["-q", "plan", str(pilot_file), "--term", "n", "--precision", "0.02",
                 "--level", "0.95", "--json", str(js)]) == 0
    doc = json.loads(js.read_text())
    assert doc["schema"] == "fogbayes.plan/1" and doc["target"]["level"] == 0.95
    assert doc["plan"]["half_width"] <= 0.02 and doc["plan"]["term"] == "N"
    assert doc["range"]["hours_low"] <= doc["plan"]["hours"] <= doc["range"]["hours_high"]


@pytest.mark.parametrize("args, needle", [
    (["--term", "K", "--precision", "0.1"], "does not resolve K"),
    (["--term", "N", "--precision", "0"], "--precision"),
    (["--term", "X", "--precision", "0.1"], "--term"),
    (["--term", "N", "--precision", "0.1", "--level", "90"], "--level"),
    # K alone would absorb the white noise (goodness-of-fit p ~ 1e-300): refused, not planned
    (["--term", "N", "--terms", "K", "--precision", "0.1"], "include --term N"),
    (["--term", "K", "--terms", "K", "--precision", "0.1"], "not described by the terms K"),
])
def test_cli_plan_bad_input_exits_2_in_one_line(pilot_file, capsys, args, needle):
    assert main(["plan", str(pilot_file), *args]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("fogbayes: error: ") and needle in err[0]
    assert "Fix:" in err[0]


def test_range_with_one_uncertain_term_is_the_plan_at_its_interval_ends():
    # Only K uncertain (sd 0.3 in log, others ~0): the 90 % region is K exp(+-z 0.3),
    # and a lower K needs a longer record, so the range ends are the plans at those values.
    from fogbayes.plan import plan_range
    from fogbayes.plan.length import z_value

    p = AllanParams(Q=0.19, N=0.01, B=0.165, K=2.0)
    cov = np.diag([1e-12, 1e-12, 1e-12, 0.3**2])
    r = plan_range(p, cov, 10.0, "K", 0.3)
    z = z_value(0.9)
    lo = plan_length(p._replace(K=2.0 * np.exp(z * 0.3)), 10.0, "K", 0.3)
    hi = plan_length(p._replace(K=2.0 * np.exp(-z * 0.3)), 10.0, "K", 0.3)
    assert r.n_low == lo.n and r.n_high == hi.n
    assert r.params_high.K == pytest.approx(hi.params.K, rel=1e-3)
    assert r.n_low <= plan_length(p, 10.0, "K", 0.3).n <= r.n_high
