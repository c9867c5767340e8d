"""Programs kept on disk once traced (fogbayes.support.stored): a second process calls the
stored module without tracing the function, with the traced program's numbers; a new key
or new shapes make a new entry; with the compile cache off nothing is written.

Each process is a fresh interpreter (a subprocess): what is checked is what a user's second
command sees. The function holds a Cholesky factorisation, an eigendecomposition and random
draws: LAPACK custom calls once crashed a fresh process that had lowered none itself.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap

SCRIPT = textwrap.dedent("""
    import json, sys
    import fogbayes  # float64, the cache folder
    import jax, jax.numpy as jnp, numpy as np
    from fogbayes.support.stored import stored

    traces = []

    def body(key, a, z):
        c = jnp.linalg.cholesky(a @ a.T + 3.0 * jnp.eye(a.shape[0]))
        w = jnp.linalg.eigh(a + a.T)[0]
        return {"c": c, "w": w, "draw": z["x"] + jax.random.normal(key, z["x"].shape)}

    def f(key, a, z):
        traces.append(1)  # runs only when JAX traces f
        return body(key, a, z)

    n, tag = int(sys.argv[1]), sys.argv[2]
    g = stored(f, ("test_stored_programs", tag))
    a = jnp.asarray(np.arange(n * n, dtype=float).reshape(n, n) / 10.0)
    args = (jax.random.PRNGKey(3), a, {"x": jnp.ones(n)})
    out = g(*args)
    ref = jax.jit(body)(*args)  # the reference: traced here, in every process
    same = all(np.array_equal(np.asarray(out[k]), np.asarray(ref[k])) for k in ref)
    print(json.dumps({"traces": len(traces), "same": bool(same)}))
""")


def _run(tmp_path, n, tag, **env):
    script = tmp_path / "stored_script.py"
    script.write_text(SCRIPT)
    res = subprocess.run([sys.executable, str(script), str(n), tag], capture_output=True,
                         text=True, timeout=300,
                         env={**os.environ, "FOGBAYES_CACHE_DIR": str(tmp_path / "cache"), **env})
    assert res.returncode == 0, res.stderr[-2000:]
    return json.loads(res.stdout.strip().splitlines()[-1])


def _entries(tmp_path):
    return sorted(p.name for p in (tmp_path / "cache").rglob("*.jaxexport"))


def test_a_second_process_runs_the_stored_program_without_tracing(tmp_path):
    assert _run(tmp_path, 3, "a") == {"traces": 1, "same": True}
    first = _entries(tmp_path)
    assert len(first) == 1
    assert _run(tmp_path, 3, "a") == {"traces": 0, "same": True}
    assert _entries(tmp_path) == first
    # other shapes: another entry, traced once (another key enters the same hash)
    assert _run(tmp_path, 4, "a") == {"traces": 1, "same": True}
    assert len(_entries(tmp_path)) == 2


def test_a_damaged_entry_is_exported_again(tmp_path):
    _run(tmp_path, 3, "a")
    (entry,) = (tmp_path / "cache").rglob("*.jaxexport")
    entry.write_bytes(entry.read_bytes()[:100])
    assert _run(tmp_path, 3, "a") == {"traces": 1, "same": True}
    assert entry.stat().st_size > 100  # written whole again


def test_nothing_is_stored_with_the_compile_cache_off(tmp_path):
    assert _run(tmp_path, 3, "a", FOGBAYES_JAX_CACHE="off") == {"traces": 1, "same": True}
    assert _entries(tmp_path) == []


def test_compiler_options_reach_the_stored_and_the_traced_program(tmp_path, monkeypatch):
    """``compiler_options`` (the pool's chains compile with LLVM's optimisations off) are
    handed to XLA whether the program is stored or, with the cache off, traced: an option
    XLA does not know is refused either way, a known one gives the function's numbers."""
    import jax.numpy as jnp
    import numpy as np
    import pytest

    from fogbayes.support.stored import stored, stored_folder

    for cache in ("on", "off"):
        monkeypatch.setenv("FOGBAYES_CACHE_DIR", str(tmp_path / cache))
        monkeypatch.setenv("FOGBAYES_JAX_CACHE", cache)
        assert (stored_folder() is None) == (cache == "off")
        bad = stored(lambda x: 2.0 * x, ("test_stored_programs", "bad", cache),
                     compiler_options={"xla_no_such_option": 1})
        with pytest.raises(Exception, match="xla_no_such_option"):
            bad(jnp.ones(3))
        good = stored(lambda x: 2.0 * x, ("test_stored_programs", "level 0", cache),
                      compiler_options={"xla_backend_optimization_level": 0})
        np.testing.assert_array_equal(np.asarray(good(jnp.arange(3.0))), [0.0, 2.0, 4.0])
