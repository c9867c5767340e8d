"""docs/calibration.md's table of effects, term kinds and what each applies to (the sensor
or the calibration run) is the code's: every term kind is listed with its own ``applies``,
and every effect the simulator plants is listed with exactly the kinds it plants (over all
its shapes)."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from fogbayes.effects.kinds import KINDS
from fogbayes.simulate.registry import EFFECTS, resolve
from fogbayes.simulate.truth import Covariates

DOC = Path(__file__).resolve().parent.parent / "docs" / "calibration.md"


def _rows() -> list[tuple[str, list[str], str]]:
    rows = []
    for line in DOC.read_text().splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) != 3 or cells[2] not in ("sensor", "run"):
            continue
        effect = re.findall(r"`([a-z0-9_]+)`", cells[0])
        rows.append((effect[0] if effect else cells[0], re.findall(r"`([a-z0-9_]+)`",
                                                                   cells[1]), cells[2]))
    return rows


def test_every_kind_is_documented_with_its_own_applies():
    documented: dict[str, str] = {}
    for _, kinds, applies in _rows():
        for k in kinds:
            assert KINDS[k].applies == applies, (k, applies)
            documented[k] = applies
    assert set(documented) == set(KINDS)


def test_every_planted_effect_is_documented_with_its_kinds():
    t = np.arange(0.0, 600.0)
    T = np.column_stack([20.0 + 0.05 * t, 19.0 + 0.05 * t])
    cov = Covariates(t, T[:, 0], T, np.full(t.size, 3.0), np.ones(t.size), None, t)
    by_effect: dict[str, set[str]] = {}
    for effect, kinds, _ in _rows():
        by_effect.setdefault(effect, set()).update(kinds)
    for name, spec in EFFECTS.items():
        if spec.terms is None:  # markov_noise: noise, not a term
            continue
        shapes = [None, {"width": 3.0}] if name == "thermal_hysteresis" else [None]
        planted = {tm.kind for params in shapes
                   for tm, _ in spec.terms(resolve(name, params, cov))}
        assert planted == by_effect.get(name, set()), (name, planted)
