"""Module docstrings state the contract and the maths: at most 5 % of the package's lines.

The share is sum over every ``.py`` file under ``fogbayes/`` of the lines of its module
docstring (``ast.get_docstring(module, clean=False)``) over the sum of the files' lines.
Narratives of what was measured or tried live in git and ``benchmarks/RESULTS*.md``.
"""

import ast
import pathlib

import fogbayes

LIMIT = 0.05


def _docstring_lines():
    root = pathlib.Path(fogbayes.__file__).parent
    rows = []
    for path in sorted(root.rglob("*.py")):
        source = path.read_text(encoding="utf-8")
        doc = ast.get_docstring(ast.parse(source), clean=False)
        rows.append((len(doc.splitlines()) if doc else 0, len(source.splitlines()),
                     str(path.relative_to(root))))
    return rows


def test_module_docstrings_are_at_most_five_percent_of_the_package():
    rows = _docstring_lines()
    doc_lines = sum(r[0] for r in rows)
    total = sum(r[1] for r in rows)
    assert total > 10_000, "the package was not found where expected"
    longest = ", ".join(f"{name} {k}" for k, _, name in sorted(rows, reverse=True)[:5])
    assert doc_lines <= LIMIT * total, (
        f"module docstrings are {doc_lines} of {total} lines ({100 * doc_lines / total:.1f} %), "
        f"over {100 * LIMIT:.0f} %; longest: {longest}. Cut narrative (what was measured, tried "
        "or compared) from the module docstrings; keep the contract and the maths.")
