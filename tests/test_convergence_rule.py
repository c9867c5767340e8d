"""One convergence rule for every posterior (fogbayes.inference.convergence): its
boundaries, and no sampler that decides convergence by a rule of its own."""

from __future__ import annotations

import math
import re
from pathlib import Path

from fogbayes.inference.convergence import R_HAT_MAX, converged, ess_floor


def test_the_rule_and_its_boundaries():
    assert converged(1.0, 400.0, 0, floor=ess_floor(2))
    assert not converged(R_HAT_MAX, 400.0, 0, floor=200.0)      # R-hat < 1.01, strictly
    assert converged(1.0, 200.0, 0, floor=200.0)                 # ESS >= floor
    assert not converged(1.0, 199.9, 0, floor=200.0)
    assert not converged(1.0, 400.0, 1, floor=200.0)             # one divergence fails
    assert not converged(math.nan, 400.0, 0, floor=200.0)        # a constant chain fails
    assert not converged(1.0, math.nan, 0, floor=200.0)
    assert ess_floor(4) == 400.0


def test_no_sampler_has_a_rule_of_its_own():
    pkg = Path(__file__).resolve().parent.parent / "fogbayes"
    own = re.compile(r"r_?hat[\w\]\)\"']*\s*<\s*(1\.01|R_HAT_MAX)")
    bad = [f"{f.relative_to(pkg)}:{i}" for f in pkg.rglob("*.py")
           if f.name != "convergence.py"
           for i, line in enumerate(f.read_text().splitlines(), 1) if own.search(line)]
    assert bad == [], bad
