"""Compiled JAX programs are kept on disk (fogbayes._config): a fresh process that runs a
program an earlier process compiled reads it instead of compiling it again.

Each case runs fresh Python processes (the cache is chosen when fogbayes is imported) with
``FOGBAYES_CACHE_DIR`` pointed at an empty folder, and counts JAX's own cache events.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

from fogbayes._config import host_tag

# A program whose compilation takes well over _config.CACHE_MIN_SECONDS (0.1 s), run once;
# prints JAX's cache events. A scan over an eigendecomposition alone compiled in 0.08-0.11 s
# on a faster 2-core box (2026-11-29: the child-folder test then found no file in 6 of 8
# runs); with a matrix exponential and a solve in the step it compiles in ~0.5 s there.
PROGRAM = """
import collections, json
import fogbayes  # noqa: F401  (chooses the cache; before JAX, as users do)
import jax, jax.monitoring, jax.numpy as jnp, jax.scipy.linalg as jsl
events = collections.Counter()
jax.monitoring.register_event_listener(lambda name, **kw: events.update([name]))

@jax.jit
def f(a):
    def body(c, _):
        w, v = jnp.linalg.eigh(c @ c.T + jnp.eye(6))
        c = jsl.expm(v * jnp.tanh(w)[None, :] / 6)
        return jnp.linalg.solve(c + jnp.eye(6), c), w.sum()
    return jax.lax.scan(body, a, None, length=8)[1].sum()

f(jnp.arange(36.0).reshape(6, 6) / 36).block_until_ready()
print(json.dumps({"dir": jax.config.jax_compilation_cache_dir,
                  "hits": events["/jax/compilation_cache/cache_hits"],
                  "misses": events["/jax/compilation_cache/cache_misses"]}))
"""


def _run(env: dict, *, jax_first: bool = False, prelude: str = "") -> dict:
    """PROGRAM in a fresh process (``jax_first``: JAX imported before fogbayes; ``prelude``:
    code run before fogbayes is imported); its JSON line, plus its stderr under "stderr"."""
    clean = {k: v for k, v in os.environ.items()
             if not k.startswith(("JAX_COMPILATION_CACHE", "FOGBAYES_JAX_CACHE", "TF_CPP_"))}
    code = ("import jax\n" if jax_first else "") + prelude + PROGRAM
    out = subprocess.run([sys.executable, "-c", code], env={**clean, **env},
                         capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    return {**json.loads(out.stdout.strip().splitlines()[-1]), "stderr": out.stderr}


def _entries(folder) -> list[str]:
    return sorted(p.name for p in folder.glob("*-cache"))


def test_a_second_process_reads_the_program_the_first_compiled(tmp_path):
    folder = tmp_path / "jax" / host_tag()  # one folder per CPU (machine code is CPU's)
    first = _run({"FOGBAYES_CACHE_DIR": str(tmp_path)})
    assert first["dir"] == str(folder)
    assert first["hits"] == 0 and first["misses"] >= 1
    written = _entries(folder)
    assert any(name.startswith("jit_f-") for name in written)
    second = _run({"FOGBAYES_CACHE_DIR": str(tmp_path)})
    # f is read, not compiled and written again. Only f's entry is compared: the small
    # helper programs (array creation, division) compile in about CACHE_MIN_SECONDS, so on
    # a loaded box one of them can be worth a file in one process and not in the other (a
    # clean-clone CI run at 18a86d3: the second process had 1 hit and 1 miss).
    assert second["hits"] >= 1
    f_entries = [name for name in written if name.startswith("jit_f-")]
    assert [name for name in _entries(folder) if name.startswith("jit_f-")] == f_entries
    # jax 0.9.2's loader logs two false SIGILL lines per program unless XLA's log is quiet
    assert "SIGILL" not in second["stderr"] and "AOT" not in second["stderr"]


def test_no_cache_where_the_loaders_false_warnings_could_not_be_silenced(tmp_path):
    # JAX imported before fogbayes: XLA's C++ log level is fixed already
    got = _run({"FOGBAYES_CACHE_DIR": str(tmp_path)}, jax_first=True)
    assert got["dir"] is None
    # the user asked for XLA's log
    got = _run({"FOGBAYES_CACHE_DIR": str(tmp_path), "TF_CPP_MIN_LOG_LEVEL": "1"})
    assert got["dir"] is None
    # ... unless the level is quiet already
    got = _run({"FOGBAYES_CACHE_DIR": str(tmp_path), "TF_CPP_MIN_LOG_LEVEL": "3"},
               jax_first=True)
    assert got["dir"] == str(tmp_path / "jax" / host_tag())


@pytest.mark.parametrize("setting", ["off", "0"])
def test_the_cache_can_be_turned_off(tmp_path, setting):
    got = _run({"FOGBAYES_CACHE_DIR": str(tmp_path), "FOGBAYES_JAX_CACHE": setting})
    assert got["dir"] is None and got["hits"] == 0
    assert not list((tmp_path).rglob("*-cache"))


def test_a_folder_the_user_gave_jax_is_kept(tmp_path):
    mine = tmp_path / "mine"
    got = _run({"FOGBAYES_CACHE_DIR": str(tmp_path / "fogbayes"),
                "JAX_COMPILATION_CACHE_DIR": str(mine)})
    assert got["dir"] == str(mine)
    assert not (tmp_path / "fogbayes" / "jax").exists()
    assert got["hits"] == 0


def test_a_folder_the_user_gave_jax_in_the_process_is_kept(tmp_path):
    # jax.config.update before fogbayes is imported: fogbayes must not replace the folder
    # (with its own, or with None because JAX was imported first)
    mine = tmp_path / "mine"
    for level in ({}, {"TF_CPP_MIN_LOG_LEVEL": "3"}):
        got = _run({"FOGBAYES_CACHE_DIR": str(tmp_path / "fogbayes"), **level},
                   jax_first=True,
                   prelude=f"jax.config.update('jax_compilation_cache_dir', {str(mine)!r})\n")
        assert got["dir"] == str(mine)
    assert not (tmp_path / "fogbayes" / "jax").exists()


def test_a_child_with_its_own_cache_folder_does_not_inherit_the_parents(tmp_path):
    # fogbayes hands its folder to JAX through the environment, which children inherit;
    # a child that names another FOGBAYES_CACHE_DIR (as the cold-cache benchmarks do) must
    # use that one, not the parent's warm cache.
    theirs = str(tmp_path / "a" / "jax" / host_tag())
    parent = {"JAX_COMPILATION_CACHE_DIR": theirs, "FOGBAYES_JAX_CACHE_SET": theirs,
              "TF_CPP_MIN_LOG_LEVEL": "3"}
    got = _run({**parent, "FOGBAYES_CACHE_DIR": str(tmp_path / "b")})
    assert got["dir"] == str(tmp_path / "b" / "jax" / host_tag())
    assert _entries(tmp_path / "b" / "jax" / host_tag())
