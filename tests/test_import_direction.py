"""Imports point one way: figures never import reports, and a model family's modules
(composite, thermal, allan, arma) form no cycle among themselves (each had one: plot/loop <-> report, compensate <->
compensate_loop). No module of fogbayes is in an import cycle, and the top-level packages form
none either (allan/arma <-> inference was one: inference sits below the families). Read from
the source with ast, so lazy imports inside functions count."""

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
        bad = [m for m in _relative_imports(f) if m.startswith(("fogbayes.render", "fogbayes.workflow"))]
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


def _import_graph() -> tuple[dict[str, set[str]], dict[str, set[str]]]:
    """(module-level, all) package-relative imports of every module of fogbayes, as
    {module: {imported modules}}; ``from pkg import name`` counts as ``pkg.name`` where that is
    a module, and imports inside functions count in the second graph only."""
    def name(f: Path) -> str:
        parts = f.relative_to(PKG.parent).with_suffix("").parts
        return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)

    files = {name(f): f for f in PKG.rglob("*.py")}
    top: dict[str, set[str]] = {m: set() for m in files}
    every: dict[str, set[str]] = {m: set() for m in files}

    def visit(node, m, parts, in_function):
        for child in ast.iter_child_nodes(node):
            if isinstance(child, ast.ImportFrom) and child.level > 0:
                base = ".".join(parts[:len(parts) - child.level]
                                + (child.module.split(".") if child.module else []))
                for alias in child.names:
                    target = f"{base}.{alias.name}"
                    target = target if target in files else base
                    every[m].add(target)
                    if not in_function:
                        top[m].add(target)
            visit(child, m, parts, in_function or isinstance(
                child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)))

    for m, f in files.items():
        visit(ast.parse(f.read_text()), m,
              list(f.relative_to(PKG.parent).with_suffix("").parts), False)
    return top, every


def _cycles(graph: dict[str, set[str]]) -> list[str]:
    """One cycle, as "a -> b -> a", through each strongly connected component of more than one
    node (Tarjan), sorted."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    components = []

    def connect(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                connect(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = set()
            while True:
                w = stack.pop()
                on_stack.discard(w)
                comp.add(w)
                if w == v:
                    break
            if len(comp) > 1:
                components.append(comp)

    for v in sorted(graph):
        if v not in index:
            connect(v)
    out = []
    for comp in components:  # the shortest way back to the first node, inside the component
        start = min(comp)
        paths = {start: [start]}
        frontier = [start]
        cycle = None
        while frontier and cycle is None:
            nxt = []
            for v in frontier:
                for w in sorted(graph[v] & comp):
                    if w == start:
                        cycle = paths[v] + [start]
                        break
                    if w not in paths:
                        paths[w] = paths[v] + [w]
                        nxt.append(w)
                if cycle:
                    break
            frontier = nxt
        out.append(" -> ".join(cycle) + f"  (component: {', '.join(sorted(comp))})")
    return sorted(out)


def test_no_module_is_in_an_import_cycle():
    """Counting lazy imports too: a function-level cycle (stats.allan <-> stats.total,
    data.documents <-> data.axes_doc were two) works only while one side stays lazy.

    The package root is left out of the graph with lazy imports: its __getattr__ is the flat
    API above everything (fogbayes.workflow.api), and modules read only ``__version__`` from
    it; among module-level imports it is a module like any other."""
    top, every = _import_graph()
    cycles = _cycles(top)
    assert not cycles, "module-level import cycle: " + "; ".join(cycles)
    no_root = {m: deps - {"fogbayes"} for m, deps in every.items() if m != "fogbayes"}
    cycles = _cycles(no_root)
    assert not cycles, "import cycle (imports inside functions count): " + "; ".join(cycles)
    for f in PKG.rglob("*.py"):  # what the root is left out for: its version, nothing else
        parts = f.relative_to(PKG.parent).with_suffix("").parts
        for node in ast.walk(ast.parse(f.read_text())):
            if isinstance(node, ast.ImportFrom) and node.level == len(parts) - 1 \
                    and not node.module:  # from <the root> import ...
                names = {a.name for a in node.names} - {m.split(".")[1] for m in every if "." in m}
                assert names <= {"__version__"}, f"{f.relative_to(PKG)} imports {names} from the root"


def test_the_top_level_packages_form_no_import_cycle():
    """Each module collapsed to its top-level package (fogbayes.allan.fit -> allan; the root
    modules errors, _config as themselves), lazy imports included: the packages are layers,
    and each imports only those below it (inference is below the model families: the families
    use its NUTS runner, convergence rule and least squares; what it needs of a family's model
    lives in models/)."""
    _, every = _import_graph()

    def package(m: str) -> str | None:
        return m.split(".")[1] if "." in m else None  # None: the root (see above)

    graph: dict[str, set[str]] = {}
    for m, deps in every.items():
        a = package(m)
        if a is None:
            continue
        graph.setdefault(a, set())
        for d in deps:
            b = package(d)
            if b is not None and b != a:
                graph[a].add(b)
    assert {"allan", "arma", "inference", "models", "stats", "data"} <= set(graph)
    cycles = _cycles(graph)
    assert not cycles, "import cycle between packages: " + "; ".join(cycles)


@pytest.mark.parametrize("shared", ["inference", "models", "stats"])
def test_a_shared_layer_imports_no_model_family(shared):
    families = ("composite", "thermal", "allan", "arma")
    _, every = _import_graph()
    bad = sorted(f"{m} -> {d}" for m, deps in every.items() if m.startswith(f"fogbayes.{shared}.")
                 for d in deps if d.split(".")[1:2] and d.split(".")[1] in families)
    assert bad == [], bad


FAMILIES = ("thermal", "composite", "allan", "arma")


def _package_imports(path: Path) -> set[str]:
    """Top-level fogbayes packages ``path`` imports (relative or absolute, lazy included;
    ``from .. import x`` counts as package x)."""
    parts = list(path.relative_to(PKG.parent).with_suffix("").parts)
    out = set()
    for node in ast.walk(ast.parse(path.read_text())):
        names = []
        if isinstance(node, ast.ImportFrom):
            mod = node.module.split(".") if node.module else []
            base = parts[:len(parts) - node.level] if node.level else []
            full = base + mod
            names = [full + [a.name] for a in node.names] if len(full) == 1 else [full]
        elif isinstance(node, ast.Import):
            names = [a.name.split(".") for a in node.names]
        out |= {n[1] for n in names if len(n) > 1 and n[0] == "fogbayes"}
    return out


#: The layers under the families (docs/DESIGN.md) and the root's modules.
BELOW = {"data", "errors", "_config", "support", "preprocess", "stats", "models", "inference",
         "__version__"}


@pytest.mark.parametrize("family", FAMILIES)
def test_a_family_imports_only_the_layers_below_it(family):
    """The families stand side by side on one floor: what two of them share (the ARMA maths,
    the fit document's basis, the operating time) lives below them (models/, preprocess/), so
    no family imports another, nor export or anything else above."""
    for f in sorted((PKG / family).rglob("*.py")):
        bad = sorted(_package_imports(f) - BELOW - {family})
        assert bad == [], f"{f.relative_to(PKG)} imports {bad}"


#: the loop's diagnosis (residuals -> findings): it reads covariates and term kinds, never a
#: family; the loop's base models (bases, gls_fit, compensate, ...) are where families enter
DIAGNOSIS = ("bartlett", "candidates", "compete", "context", "elpd", "evidence", "fitting",
             "markov", "noise_prior", "nullsim", "refine", "reml", "scans")


def test_the_loop_diagnosis_imports_no_family():
    for name in DIAGNOSIS:
        f = PKG / "loop" / f"{name}.py"
        bad = sorted(_package_imports(f) & set(FAMILIES))
        assert bad == [], f"{f.relative_to(PKG)} imports the family {bad}"
