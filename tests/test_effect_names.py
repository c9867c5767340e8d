"""Each effect is named in one place: its name stands as a string in at most two modules of
fogbayes (its own effect module, and at most one more), so code reads the name from the
registry's class. Read from the source with ast: a string constant equal to the name counts,
``__all__`` entries (a function that shares the name) do not, and a name that is also a term
kind's (``step``, ``periodic``) is left out: the kind is its own concept."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

from fogbayes import effects
from fogbayes.effects.terms import KINDS

PKG = Path(__file__).resolve().parent.parent / "fogbayes"


def _strings(path: Path) -> set[str]:
    tree = ast.parse(path.read_text())
    listed = {id(c) for node in ast.walk(tree) if isinstance(node, ast.Assign)
              and any(isinstance(t, ast.Name) and t.id == "__all__" for t in node.targets)
              for c in ast.walk(node.value)}
    return {n.value for n in ast.walk(tree) if isinstance(n, ast.Constant)
            and isinstance(n.value, str) and id(n) not in listed}


STRINGS = {f.relative_to(PKG).as_posix(): _strings(f) for f in PKG.rglob("*.py")}


@pytest.mark.parametrize("name", sorted(set(effects.REGISTRY) - set(KINDS)))
def test_an_effect_name_stands_in_at_most_two_modules(name):
    where = sorted(m for m, s in STRINGS.items() if name in s)
    assert len(where) <= 2, f"{name!r} stands as a string in {where}"
