"""The flat API of ``import fogbayes`` (fit, compensate, run_loop, allan_deviation): the same
results as the modules the command line uses, resolved on first use (importing fogbayes
starts no JAX), and no name that a subpackage would shadow."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

import fogbayes
from fogbayes.simulate import simulate
from fogbayes.stats.allan import allan_deviation
from fogbayes.thermal.workflow import compensate_recording, fit_recording


def test_import_fogbayes_starts_no_jax():
    code = "import sys, fogbayes; print('jax' in sys.modules, 'numpyro' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["False", "False"]


def test_flat_names_are_the_workflow_functions():
    rec = simulate("thermal", seed=3, duration=3600.0, fs=1.0).recording
    doc = fogbayes.fit(rec, model="thermal", orders="2,1")
    ref = fit_recording(rec, model="thermal", orders="2,1")
    np.testing.assert_array_equal(doc["params"]["coef"], ref["params"]["coef"])
    comp = fogbayes.compensate(rec, doc)
    np.testing.assert_array_equal(comp["output"], compensate_recording(rec, ref)["output"])
    assert fogbayes.allan_deviation is allan_deviation
    assert callable(fogbayes.run_loop)
    with pytest.raises(fogbayes.FogbayesError, match="nothing to compensate"):
        fogbayes.compensate(rec, {"model": "allan"})
    with pytest.raises(AttributeError):
        fogbayes.no_such_name  # noqa: B018
    static = simulate("static", seed=1, duration=600.0, fs=10.0).recording
    with pytest.raises(fogbayes.FogbayesError, match="candidates"):  # never silently ignored
        fogbayes.fit(static, model="arma", orders="1,1")


def test_every_public_name_resolves_and_no_subpackage_is_shadowed():
    import importlib
    import pkgutil

    subpackages = {m.name for m in pkgutil.iter_modules(fogbayes.__path__)}
    assert not set(fogbayes.__all__) & subpackages
    for name in fogbayes.__all__:
        assert getattr(fogbayes, name) is not None
    assert importlib.import_module("fogbayes.simulate").simulate is simulate
