"""Each numerical service has one owner module (docs/DESIGN.md, "Layout"): the information
criteria (ArviZ's loo/waic/compare) only in inference/compare.py, optax L-BFGS only in
inference/lsq.py, SciPy's L-BFGS-B only in inference/lbfgsb.py. Read from the source with
ast, so a second copy written anywhere in the package fails here."""

from __future__ import annotations

import ast
from pathlib import Path

PKG = Path(__file__).resolve().parent.parent / "fogbayes"


def _callers(pred) -> set[str]:
    out = set()
    for f in PKG.rglob("*.py"):
        for node in ast.walk(ast.parse(f.read_text())):
            if isinstance(node, ast.Call) and pred(node):
                out.add(f.relative_to(PKG).as_posix())
    return out


def _attr_call(owner: str, names: set[str]):
    def pred(node: ast.Call) -> bool:
        fn = node.func
        return (isinstance(fn, ast.Attribute) and fn.attr in names
                and isinstance(fn.value, ast.Name) and fn.value.id == owner)
    return pred


def _lbfgsb(node: ast.Call) -> bool:
    return any(k.arg == "method" and isinstance(k.value, ast.Constant)
               and str(k.value.value).upper() == "L-BFGS-B" for k in node.keywords)


def _imports_from(module: str, names: set[str]) -> set[str]:
    out = set()
    for f in PKG.rglob("*.py"):
        for node in ast.walk(ast.parse(f.read_text())):
            if isinstance(node, ast.ImportFrom) and (node.module or "").startswith(module) \
                    and any(a.name in names for a in node.names):
                out.add(f.relative_to(PKG).as_posix())
    return out


def test_information_criteria_have_one_owner():
    ic = {"loo", "waic", "compare"}
    assert (_callers(_attr_call("az", ic)) | _callers(_attr_call("arviz", ic))
            ) == {"inference/compare.py"}
    assert not _imports_from("arviz", ic)


def test_optax_lbfgs_has_one_owner():
    assert _callers(_attr_call("optax", {"lbfgs"})) == {"inference/lsq.py"}


def test_scipy_lbfgsb_has_one_owner():
    assert _callers(_lbfgsb) == {"inference/lbfgsb.py"}
    assert not _imports_from("scipy.optimize", {"fmin_l_bfgs_b"})
