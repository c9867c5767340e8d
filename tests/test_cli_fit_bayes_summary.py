"""``fogbayes fit --bayes`` prints the posterior, as the fit document holds it.

Each raw coefficient's posterior mean and interval, and the sampler's R-hat, effective
sample size and divergences, read back from the document the same command wrote: the
printed numbers are the document's to the 4 significant digits printed.
"""

from __future__ import annotations

import json
import re

import pytest

from fogbayes.cli import main
from fogbayes.data import save
from fogbayes.simulate import simulate


@pytest.fixture(scope="module")
def rec(tmp_path_factory):
    d = tmp_path_factory.mktemp("bayesline")
    return save(simulate("thermal", seed=1, duration=1200.0, fs=1.0).recording, d / "rec.csv")


def test_thermal_bayes_prints_the_posterior_of_the_document(rec, tmp_path, capsys):
    out = tmp_path / "fit.json"
    assert main(["fit", str(rec), "-m", "thermal", "--bayes", "--json", str(out)]) == 0
    err = capsys.readouterr().err
    doc = json.loads(out.read_text())
    raw, conv = doc["bayes"]["raw"], doc["bayes"]["convergence"]
    assert "thermal posterior (NUTS" in err, err
    assert "90% interval" in err, err
    lines = err.splitlines()
    for term, mean, (lo, hi) in zip(raw["terms"], raw["mean"], raw["interval"]):
        label = "constant" if term == "1" else term
        line = next((ln for ln in lines if ln.strip().startswith(f"{label}:")), None)
        assert line is not None, (term, err)
        m = re.match(r"\s*[^:]+: (\S+) \[(\S+), (\S+)\]", line)
        assert m, line
        for shown, true in zip(map(float, m.groups()), (mean, lo, hi)):
            assert shown == pytest.approx(true, rel=5e-4, abs=1e-12), (line, true)
    # the printed means are the posterior's, not the least-squares coefficients
    ls = doc["params"]["raw"]["coef"]
    assert any(abs(m - c) > 1e-3 * abs(c) for m, c in zip(raw["mean"], ls))
    verdict = next(ln for ln in lines if ln.startswith("sampler: "))
    rhat = float(re.search(r"R-hat max (\S+),", verdict).group(1))
    assert rhat == pytest.approx(conv["r_hat_max"], abs=5e-4)
    assert f"{conv['divergences']} divergences" in verdict
    assert verdict.endswith("converged" if conv["converged"] else "intervals")


def test_without_bayes_no_posterior_is_printed(rec, tmp_path, capsys):
    assert main(["fit", str(rec), "-m", "thermal", "--json", str(tmp_path / "f.json")]) == 0
    assert "posterior" not in capsys.readouterr().err
