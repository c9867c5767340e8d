"""The paper-000 notebook is committed without outputs.

CI executes it with nbmake (pyproject addopts); its last cell asserts the paper's table
layout, the 2-step baseline and the exact inversion, so a wrong number fails CI there.
"""

from pathlib import Path

import pytest

NB = Path(__file__).resolve().parents[1] / "notebooks" / "composite_paper000.ipynb"


def test_notebook_is_stored_without_outputs():
    nbformat = pytest.importorskip("nbformat")
    nb = nbformat.read(NB, as_version=4)
    code = [c for c in nb.cells if c.cell_type == "code"]
    assert code and all(not c.outputs and c.execution_count is None for c in code)
