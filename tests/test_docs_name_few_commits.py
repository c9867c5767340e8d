"""Documents are for their readers: README names no commit, each RESULTS file at most two.

History (what was tried, old timings, which commit did what) lives in git. A commit is a
7-40 character hexadecimal word holding both a letter and a digit (a number such as
0.0349065850398866 is not one).
"""

import pathlib
import re

ROOT = pathlib.Path(__file__).resolve().parents[1]
HEX = re.compile(r"\b[0-9a-f]{7,40}\b")


def commits_in(text: str) -> set[str]:
    return {w for w in HEX.findall(text) if re.search("[a-f]", w) and re.search("[0-9]", w)}


def commits(path: pathlib.Path) -> set[str]:
    return commits_in(path.read_text(encoding="utf-8"))


def test_the_rule_finds_commits_and_passes_numbers_and_words():
    text = "code f0588ae (a 7-digit id), 0.0349065850398866, 1234567, deadbeef, facade"
    assert commits_in(text) == {"f0588ae"}


def test_readme_names_no_commit():
    assert commits(ROOT / "README.md") == set()


def test_each_results_file_names_at_most_two_commits():
    files = sorted((ROOT / "benchmarks").glob("RESULTS*.md"))
    assert files
    over = {f.name: sorted(commits(f)) for f in files if len(commits(f)) > 2}
    assert not over, over
