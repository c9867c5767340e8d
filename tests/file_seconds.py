"""Write ``tests/file_seconds.json``: seconds per test file, from a JUnit XML of a suite run.

    python3 -m pytest -q -n 2 --dist loadfile --junitxml=/tmp/suite.xml
    python3 tests/file_seconds.py /tmp/suite.xml "2026-11-28, 226272d, the 2-core CI box"

``conftest.pytest_collection_modifyitems`` sends the slowest files first, so that the last
file a worker takes is a short one (longest-processing-time-first order). Stale figures
cost only balance, never a result: a file missing from the table counts as the median.
"""

from __future__ import annotations

import collections
import json
import sys
import xml.etree.ElementTree as ET
from pathlib import Path


def file_of(classname: str) -> str:
    """JUnit classname -> pytest path: 'tests.test_x.TestY' -> 'tests/test_x.py',
    'notebooks.nb.ipynb' -> 'notebooks/nb.ipynb'."""
    if classname.endswith(".ipynb"):
        folder, name = classname.split(".", 1)
        return f"{folder}/{name}"
    parts = classname.split(".")
    return "/".join(parts[:2]) + ".py"


def main(xml: str, measured: str) -> None:
    seconds: dict[str, float] = collections.Counter()
    for case in ET.parse(xml).getroot().iter("testcase"):
        seconds[file_of(case.get("classname"))] += float(case.get("time"))
    table = {"measured": measured,
             "seconds": {f: round(s, 1) for f, s in sorted(seconds.items(), key=lambda x: -x[1])}}
    out = Path(__file__).with_suffix(".json")
    out.write_text(json.dumps(table, indent=1) + "\n")
    print(f"{len(seconds)} files, {sum(seconds.values()):.0f} s -> {out}")


if __name__ == "__main__":
    main(*sys.argv[1:3])
