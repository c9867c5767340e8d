"""Messages call a document key a field and a command-line flag an option, not a column
(issue 55): "column 'model'" sent users looking for a column in their recording.
"""

from __future__ import annotations

import json

import pytest

from fogbayes import save
from fogbayes.cli import main
from fogbayes.errors import FogbayesError
from fogbayes.simulate import simulate


def test_error_names_what_kind_of_place():
    """The one format: ``file, <kind> '<name>', row r (line l): problem. Fix: ...``."""
    assert str(FogbayesError("p", file="a.json", field="params.spec", fix="f")) == \
        "a.json, field 'params.spec': p. Fix: f"
    assert str(FogbayesError("p", flag="--term")) == "option '--term': p"
    assert str(FogbayesError("p", column="--term")) == "option '--term': p"  # a flag, whatever
    assert str(FogbayesError("p", file="r.csv", column="time", row=3)) == \
        "r.csv, column 'time', row 3: p"
    e = FogbayesError("p", field="K")
    assert e.column == "K" and e.kind == "field"  # the name stays readable as before


def run(capsys, *args) -> tuple[int, str]:
    capsys.readouterr()
    rc = main([str(a) for a in args])
    err = capsys.readouterr().err.strip()
    assert "Traceback" not in err and len(err.splitlines()) == 1, err
    return rc, err


@pytest.fixture(scope="module")
def static(tmp_path_factory):
    d = tmp_path_factory.mktemp("fields")
    save(simulate("static", duration=1800.0, fs=1.0, seed=5).recording, d / "s.csv")
    assert main(["-q", "allan", str(d / "s.csv"), "--json", str(d / "adev.json")]) == 0
    assert main(["-q", "prior", "--arw", "0.05", "--arw-unit", "deg/sqrt(h)", "--json",
                 str(d / "prior.json")]) == 0
    return d


@pytest.mark.parametrize("stream", [False, True])
def test_noise_document_as_params_names_its_field(static, capsys, tmp_path, stream):
    """An Allan document has nothing to compensate: the document and its 'model' field are
    named (it used to be "column 'model'" and, without --stream, no file)."""
    save(simulate("static", duration=600.0, fs=1.0, seed=6).recording, tmp_path / "s.npz")
    rc, err = run(capsys, "compensate", tmp_path / "s.npz", "-p", static / "adev.json", "-o",
                  tmp_path / "c.npz", *(["--stream"] if stream else []))
    assert rc == 2
    assert f"{static / 'adev.json'}, field 'model'" in err and "column" not in err


def test_prior_document_unit_is_a_field(static, capsys, tmp_path):
    doc = json.loads((static / "prior.json").read_text())
    doc["terms"]["N"]["unit"] = "deg/h"
    bad = tmp_path / "bad_prior.json"
    bad.write_text(json.dumps(doc))
    rc, err = run(capsys, "allan", static / "s.csv", "--bayes", "--prior", bad,
                  "--json", tmp_path / "a.json")
    assert rc == 2 and f"{bad}, field 'terms.N.unit'" in err


def test_noise_prior_value_is_a_field(static, capsys, tmp_path):
    bad = tmp_path / "k.json"
    bad.write_text('{"K": -1}')
    rc, err = run(capsys, "loop", static / "s.csv", "-m", "bias-t", "--noise-prior", bad,
                  "--json", tmp_path / "l.json", "--compensated", tmp_path / "lc.csv")
    assert rc == 2 and f"{bad}, field 'K'" in err


def test_flag_is_an_option(static, capsys, tmp_path):
    rc, err = run(capsys, "allan", static / "s.csv", "--prior", static / "prior.json",
                  "--json", tmp_path / "a.json")
    assert rc == 2 and "option '--prior'" in err and "column" not in err


def test_multi_axis_document_of_another_version_is_one_line(static, capsys, tmp_path):
    """A multi-axis document this version does not read: one line naming its field (the
    check raised a TypeError before)."""
    ax = tmp_path / "axes.json"
    ax.write_text(json.dumps({"schema": "fogbayes.axes/2", "model": "allan", "axes": {}}))
    rc, err = run(capsys, "compensate", static / "s.csv", "-p", ax, "-o", tmp_path / "c.csv")
    assert rc == 2 and str(ax) in err and "'schema'" in err and "fogbayes.axes/1" in err


@pytest.mark.parametrize("command", [["fit", "--json", "f.json"], ["loop", "--report", "l.html"]])
def test_unknown_model_names_the_option(static, capsys, tmp_path, command):
    """``-m foo`` is the --model option, not a column of the recording."""
    rc, err = run(capsys, command[0], static / "s.csv", "-m", "foo", command[1],
                  tmp_path / command[2])
    assert rc == 2 and "option '--model': unknown model 'foo'" in err


def test_a_function_argument_is_called_an_argument_not_a_column():
    """``allan_deviation(x, taus=[0])`` said "column 'taus'" though no table is involved."""
    import numpy as np

    from fogbayes.errors import FogbayesError
    from fogbayes.stats.allan import allan_deviation

    with pytest.raises(FogbayesError) as info:
        allan_deviation(np.random.default_rng(0).normal(size=1000), 1.0, taus=[0])
    assert "argument 'taus'" in str(info.value) and "column" not in str(info.value)
    assert info.value.kind == "argument"
