"""The notebooks use the public API and say the counts their figures show (issue 55).

A notebook is what a new user copies: it calls ``fogbayes.fit`` / ``fogbayes.compensate``
(the functions the command line runs, :mod:`fogbayes.workflow.api`), never a workflow
module's internals; and a printed count of flagged samples is the count of the array its
figure draws (the paper 004 notebook printed the fit's 399 beside a legend of 396).
"""

from __future__ import annotations

import ast
import json
import re
from pathlib import Path

import pytest

NOTEBOOKS = sorted((Path(__file__).resolve().parents[1] / "notebooks").glob("*.ipynb"))
INTERNAL = ("fit_recording", "compensate_recording", "analyse_recording")


def _code(path: Path) -> str:
    cells = json.loads(path.read_text(encoding="utf-8"))["cells"]
    src = ["".join(c["source"]) for c in cells if c["cell_type"] == "code"]
    # IPython magics and shell lines are not Python
    return "\n".join(ln for s in src for ln in s.splitlines() if not ln.lstrip().startswith(("%", "!")))


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.name for p in NOTEBOOKS])
def test_notebooks_call_the_public_api(path):
    tree = ast.parse(_code(path))
    imported = {(n.module, a.name) for n in ast.walk(tree) if isinstance(n, ast.ImportFrom)
                for a in n.names}
    bad = sorted(f"{m}.{a}" for m, a in imported if a in INTERNAL)
    assert not bad, f"{path.name} imports {bad}: use fogbayes.fit / fogbayes.compensate"
    called = {n.func.id for n in ast.walk(tree) if isinstance(n, ast.Call)
              and isinstance(n.func, ast.Name)}
    assert not called & set(INTERNAL)


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.name for p in NOTEBOOKS])
def test_a_printed_flag_count_is_the_one_the_figure_draws(path):
    """Every print that says how many samples are flagged of the record counts the array
    passed to ``plot_recording(..., outliers=...)`` in that notebook."""
    tree = ast.parse(_code(path))
    drawn = {ast.unparse(k.value) for n in ast.walk(tree) if isinstance(n, ast.Call)
             and ast.unparse(n.func).endswith("plot_recording")
             for k in n.keywords if k.arg == "outliers"}
    if not drawn:
        pytest.skip("no recording figure with flags")
    prints = [ast.unparse(n) for n in ast.walk(tree) if isinstance(n, ast.Call)
              and isinstance(n.func, ast.Name) and n.func.id == "print"
              and "flagged" in ast.unparse(n) and re.search(r"of \{\w+\.n\}", ast.unparse(n))]
    assert prints
    for p in prints:
        first = p.split("flagged", 1)[1][:200]  # the count right after the word
        assert any(re.search(rf"\b{re.escape(v)}(\.sum\(\)|\.mean\(\))", first) for v in drawn), p
