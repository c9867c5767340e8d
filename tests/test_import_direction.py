"""Imports point one way: figures never import reports, and a model family's modules
(composite, thermal, allan, arma) form no cycle among themselves (each had one: plot/loop <-> report, compensate <->
compensate_loop). Read from the source with ast, so lazy imports inside functions count."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PKG = Path(__file__).resolve().parent.parent / "fogbayes"


def _relative_imports(path: Path) -> set[str]:
    """Absolute dotted names of the package-relative imports of ``path``."""
    parts = list(path.relative_to(PKG.parent).with_suffix("").parts)
    out = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom) and node.level > 0:
            base = parts[:len(parts) - node.level]
            out.add(".".join(base + (node.module.split(".") if node.module else [])))
    return out


def test_no_figure_module_imports_a_report():
    for f in sorted((PKG / "plot").glob("*.py")):
        bad = [m for m in _relative_imports(f) if m.startswith("fogbayes.report")]
        assert bad == [], f"{f.name} imports {bad}"


def test_the_data_layer_imports_nothing_above_it():
    """data is the bottom layer: recordings, files, documents. A family's document rules
    live in the family and are named in data.documents.MODEL_CHECKS, not imported."""
    below = ("fogbayes.data", "fogbayes.errors", "fogbayes.data.units", "fogbayes._config",
             "fogbayes.support")
    for f in sorted((PKG / "data").glob("*.py")):
        bad = [m for m in _relative_imports(f)
               if m != "fogbayes" and not m.startswith(below)]
        assert bad == [], f"data/{f.name} imports {bad}"


def test_the_package_root_holds_only_the_api_errors_and_config():
    """Everything else lives in a package that says what it is for (docs/DESIGN.md)."""
    loose = sorted(f.name for f in PKG.glob("*.py"))
    assert loose == ["__init__.py", "__main__.py", "_config.py", "errors.py"], loose


def test_support_imports_no_model_family():
    """support/ sits under every family: it may use errors and config, nothing above."""
    for f in sorted((PKG / "support").glob("*.py")):
        bad = [m for m in _relative_imports(f)
               if m not in ("fogbayes", "fogbayes.errors", "fogbayes._config")
               and not m.startswith("fogbayes.support")]
        assert bad == [], f"support/{f.name} imports {bad}"


@pytest.mark.parametrize("family", ["composite", "thermal", "allan", "arma"])
def test_a_family_package_has_no_import_cycle(family):
    mods = {f"fogbayes.{family}.{f.stem}": _relative_imports(f)
            for f in (PKG / family).glob("*.py") if f.stem != "__init__"}
    graph = {m: {t for t in deps if t in mods} for m, deps in mods.items()}
    state: dict[str, int] = {}

    def visit(m, path):
        state[m] = 1
        for t in graph[m]:
            assert state.get(t) != 1, f"import cycle: {' -> '.join(path + [m, t])}"
            if t not in state:
                visit(t, path + [m])
        state[m] = 2

    for m in graph:
        if m not in state:
            visit(m, [])
    if family in ("composite", "thermal"):  # the workflow uses its family's one compensator
        assert f"fogbayes.{family}.compensate" in graph[f"fogbayes.{family}.workflow"]


def test_every_source_compiles_without_a_warning():
    # an unknown escape in a docstring ("\l" in ":math:`\log`") warns today and is a syntax
    # error in a later Python; "\t" in ":math:`r^\top`" is silently a tab. Raw strings fix both.
    import warnings
    for f in sorted(PKG.rglob("*.py")):
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            compile(f.read_text(), str(f), "exec")
