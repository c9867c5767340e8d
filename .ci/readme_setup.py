"""Print set-up command N (1 or 2) of README.md's "Set up" section, exactly as written.

.ci/run runs the README's commands through this script so that CI runs them verbatim:
an edit of the README is an edit of CI.
"""

import re
import sys
from pathlib import Path

readme = (Path(__file__).resolve().parents[1] / "README.md").read_text()
section = readme.split("\n## Set up", 1)[1].split("\n## ", 1)[0]
blocks = re.findall(r"^```[a-z]*\n(.*?)^```", section, flags=re.S | re.M)
if len(blocks) != 2 or any(len(b.strip().splitlines()) != 1 for b in blocks):
    sys.exit("README.md 'Set up' must hold exactly two one-line commands in code blocks")
print(blocks[int(sys.argv[1]) - 1].strip())
