"""fogbayes bounds the memory maps its compiled programs hold (fogbayes.support.programs).

Reference: the kernel's own count of this process's maps (/proc/self/maps), before and
after; and the numbers of a fit, equal before and after its program was dropped.
"""

from __future__ import annotations

import sys

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from fogbayes.arma.fit import _fit_arma, fit_arma
from fogbayes.support import programs

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"),
                                reason="memory maps are counted from /proc/self/maps (Linux)")


def test_release_frees_the_maps_of_fogbayes_programs_only():
    """An ARMA fit's program holds > 500 maps (~1 100-1 450 measured); dropping fogbayes's
    programs gives them back, a user's own jitted function keeps its compiled code, and the
    fit recompiled afterwards returns the same numbers."""
    x = np.random.default_rng(3).standard_normal(1500)
    user = jax.jit(lambda v: jnp.cumsum(v) * 2.0)
    user(jnp.ones(7)).block_until_ready()
    programs.release_programs()
    before = programs.memory_maps()
    first = fit_arma(x, p=2, q=1)
    held = programs.memory_maps()
    assert held - before > 500, (before, held)
    assert _fit_arma._cache_size() == 1
    programs.release_programs()
    assert _fit_arma._cache_size() == 0
    assert programs.memory_maps() < held - 500
    assert user._cache_size() == 1  # not fogbayes's: left alone
    again = fit_arma(x, p=2, q=1)
    np.testing.assert_array_equal(np.asarray(again.phi), np.asarray(first.phi))
    assert float(again.loglik) == float(first.loglik)


def test_a_compilation_past_the_limit_drops_the_other_programs(monkeypatch):
    """Past the limit, the program that just compiled keeps its code and every other one
    is dropped, so 16 new programs (~17 maps each, measured) cannot raise the count by
    more than ~one program above the limit; without the bound they add ~270."""
    programs.release_programs()
    start = programs.memory_maps()
    limit = start + 60
    monkeypatch.setattr(programs, "map_limit", lambda: limit)
    monkeypatch.setattr(programs, "REGROW_SHARE", 0.0)  # release at the limit itself
    monkeypatch.setitem(programs._released, "warned", True)  # the warning: the next test
    made, peak = [], 0
    for k in range(16):
        prog = programs.program(lambda v, k=k: jnp.sin(v) * k + jnp.cumsum(v))
        prog(jnp.arange(5.0 + k)).block_until_ready()
        made.append(prog)
        peak = max(peak, programs.memory_maps())
    assert programs.releases() > 0
    assert made[-1]._cache_size() == 1  # the newest program was kept
    assert sum(p._cache_size() for p in made[:-1]) < len(made) - 1
    assert peak < limit + 120, (start, limit, peak)


def test_maps_held_elsewhere_do_not_make_every_compilation_release(monkeypatch):
    """Maps fogbayes cannot give back (here a count stuck past the limit) make one release
    and one warning, not a release (and a recompilation of everything) per compilation:
    the next release waits for REGROW_SHARE of the kernel's limit of new maps."""
    monkeypatch.setattr(programs, "map_limit", lambda: 1_000)
    monkeypatch.setattr(programs, "max_map_count", lambda: 65_530)
    monkeypatch.setattr(programs, "memory_maps", lambda: 9_000)  # > 8 191 = REGROW of 0
    monkeypatch.setitem(programs._released, "left", 0)
    monkeypatch.setitem(programs._released, "warned", False)
    before = programs.releases()
    with pytest.warns(RuntimeWarning, match="vm.max_map_count"):
        for k in range(5):
            programs.program(lambda v, k=k: jnp.cos(v) + k)(jnp.arange(3.0 + k))
    assert programs.releases() - before == 1
    assert programs.release_threshold() == 9_000 + int(programs.REGROW_SHARE * 65_530)


def test_program_is_the_jitted_function():
    """Same value, same static arguments and attributes as ``jax.jit``, and usable in
    other transformations (traced calls do not count as compilations)."""
    f = programs.program(lambda x, n: x ** n, static_argnames=("n",))
    g = jax.jit(lambda x, n: x ** n, static_argnames=("n",))
    assert float(f(3.0, n=2)) == float(g(3.0, n=2)) == 9.0
    assert float(jax.grad(lambda x: f(x, n=3))(2.0)) == 12.0
    assert np.allclose(jax.vmap(lambda x: f(x, n=2))(jnp.arange(3.0)), [0.0, 1.0, 4.0])
    assert f.lower(1.0, n=2).compile() is not None


def test_fogbayes_compiles_only_through_program():
    """Every jit in fogbayes goes through the bound (a bare ``jax.jit`` would hold its code
    past the limit); mentions in backquotes (documentation) do not count."""
    import re
    from pathlib import Path

    import fogbayes

    root = Path(fogbayes.__file__).parent
    bare = re.compile(r"(?<!`)\bjax\.jit\b|\bfrom jax import [^\n]*\bjit\b")
    found = [f"{path.relative_to(root)}:{i}" for path in sorted(root.rglob("*.py"))
             if path.name != "programs.py"
             for i, line in enumerate(path.read_text().splitlines(), 1)
             if bare.search(line.split("#")[0])]
    assert found == [], f"use fogbayes.support.programs.program instead of jax.jit: {found}"
