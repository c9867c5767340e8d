"""A pool of four 1 h static units whose records do not resolve B and K on their own
(``fogbayes simulate static --seed 11..14``, 10 Hz; true N 0.005 deg/sqrt(h), B 0.02 deg/h,
K 0.05 deg/h^1.5, R 0 for every unit): what the pool states holds the simulation truth, and
a term the population does not resolve is stated as an upper bound, never as a median with
an interval, in the document, on the command line and in the report.

The figures of 20 such pools (80 units, at 10 Hz and at 1 Hz) are in
benchmarks/RESULTS_pool.md (benchmarks/bench_pool_short.py).
"""

from __future__ import annotations

import contextlib
import io
import json
import re

import pytest

TRUTH = {"N": 0.005, "B": 0.02, "K": 0.05}


@pytest.fixture(scope="module")
def units(tmp_path_factory):
    from fogbayes.data import save
    from fogbayes.simulate import simulate

    d = tmp_path_factory.mktemp("short") / "units"
    for seed in (11, 12, 13, 14):
        sim = simulate("static", seed=seed)
        assert sim.truth.params["noise"] == TRUTH
        save(sim.recording, d / f"u{seed}.csv")
    return d


def _pool(units, *args):
    """``fogbayes pool UNITS/ ARGS`` -> (the channel's pool, stderr, the report's HTML)."""
    from fogbayes.cli import main

    out, rep = units.parent / "pool.json", units.parent / "pool.html"
    for f in (out, rep):
        f.unlink(missing_ok=True)
    err = io.StringIO()
    with contextlib.redirect_stderr(err):
        code = main(["pool", str(units), *args, "--json", str(out), "--report", str(rep)])
    assert code == 0
    return json.loads(out.read_text())["channels"]["output"], err.getvalue(), rep.read_text()


@pytest.fixture(scope="module")
def pooled(units):
    return _pool(units)


def test_the_truth_lies_within_what_the_population_states(pooled):
    """Units leave B or K unresolved; the population median's 90 % interval holds the truth
    (or, for a term the population does not resolve, [0, bound] does). A normal prior of sd
    10 on log mu and the unresolved terms' likelihood left flat below once put B at 1.9e-5
    deg/h [7.7e-11, 0.0096] and K at 5.4e-5 [7.8e-11, 0.027]: both below the truth."""
    pool, err, _ = pooled
    # Such pools can end with the sampler's diagnostics outside the rule (2 of the 20 of
    # benchmarks/RESULTS_pool.md, one divergence each): then the command must say so, and
    # what it states must still hold the truth.
    assert pool["converged"] or "converge" in err.lower(), err
    # the records are short enough that units leave B or K unresolved: the path under test
    assert sum(not u["terms"][t]["single"]["resolved"] for u in pool["units"]
               for t in ("B", "K")) >= 4
    for t, true in TRUTH.items():
        p = pool["population"][t]
        m = p["median"]
        if p.get("resolved", True):
            assert m["low"] <= true <= m["high"], (t, m)
        else:
            assert true <= m["upper"], (t, m)
    n = pool["population"]["N"]  # measured to ~1 % by each unit
    assert n["resolved"] and n["median"]["high"] / n["median"]["low"] < 1.05


def _check_statements(pool, err, html):
    """Each term is an interval with its spread, or a bound with none, in all three places."""
    for t in pool["terms"]:
        p = pool["population"][t]
        m = p["median"]
        unit = re.escape(m["unit"])
        line = re.search(rf"^  {t} population (.*)$", err, re.M).group(1)
        row = re.search(rf"<tr><td>{t}</td>(.*?)</tr>", html, re.S).group(1)
        if p["resolved"]:
            assert {"value", "low", "high"} <= set(m) and p["spread"] is not None
            ev = p["evidence"]
            assert ev["chi2_absent"] is None or ev["chi2_absent"] >= ev["threshold"]
            assert re.match(rf"[0-9.e-]+ \[[0-9.e-]+, [0-9.e-]+\] {unit}, units differ", line)
            assert "&lt;" not in row and "[" in row
            continue
        assert set(m) == {"upper", "level", "unit"} and m["level"] == 0.95, m
        assert p["spread"] is None and set(p["new_unit"]) == {"upper", "level", "unit"}
        ev = p["evidence"]  # the records do not exclude the term's absence in every unit
        assert 0 <= ev["chi2_absent"] < ev["threshold"] == pytest.approx(2.706, abs=1e-3)
        for u in pool["units"]:
            pooled = u["terms"][t]["pooled"]
            assert ("upper" in pooled) != u["terms"][t]["single"]["resolved"], pooled
        assert re.match(rf"< [0-9.e-]+ {unit} \(95 %\): not resolved", line), line
        assert "&lt; " in row and "not resolved" in row and "[" not in row, row


def test_resolved_terms_are_stated_as_intervals(pooled):
    _check_statements(*pooled)


def test_an_unresolved_term_is_stored_printed_and_reported_as_an_upper_bound(units):
    """R (a rate ramp; 0 in the simulation) pooled with N: no record can tell it from 0, so
    the population states R < bound (95 %) only: no median, interval or spread, which would
    be the prior's. The truth 0 lies below any bound; N stays an interval."""
    pool, err, html = _pool(units, "--terms", "N,R")
    assert pool["population"]["R"]["resolved"] is False
    assert pool["population"]["N"]["resolved"] is True
    _check_statements(pool, err, html)
