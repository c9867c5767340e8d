"""CI runs what the README tells users to run: its two set-up commands, verbatim, in order.

The README's "Set up" section holds exactly two one-line commands (install + demo; test
extras + the whole suite); ``.ci/run`` must contain each as a line of its own, the first
before the second.
"""

from __future__ import annotations

import re
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]


def readme_setup_commands() -> list[str]:
    section = (REPO / "README.md").read_text(encoding="utf-8").split("\n## Set up", 1)[1]
    section = section.split("\n## ", 1)[0]
    return [b.strip() for b in re.findall(r"^```[a-z]*\n(.*?)^```", section, flags=re.S | re.M)]


def test_the_readme_has_two_one_line_setup_commands():
    cmds = readme_setup_commands()
    assert len(cmds) == 2 and all("\n" not in c for c in cmds), cmds
    assert "fogbayes demo" in cmds[0] and "pytest" in cmds[1]


def test_ci_runs_both_commands_verbatim_and_in_order():
    lines = [ln.strip() for ln in (REPO / ".ci" / "run").read_text().splitlines()]
    first, second = readme_setup_commands()
    assert first in lines and second in lines
    assert lines.index(first) < lines.index(second)
