"""Numerical configuration applied when fogbayes is imported.

fogbayes fits in float64: the papers' coefficients span 1e1 ... 1e-12 and Allan variances
span many decades, so single precision loses the answer. Importing fogbayes therefore turns
on JAX's 64-bit mode (``jax_enable_x64``), the same switch as ``JAX_ENABLE_X64=1`` or
``numpyro.enable_x64()``. Arrays created with an explicit ``dtype=jnp.float32`` stay
float32, which is how the compensators run in single precision when asked.

JAX is not imported here (0.5 s): ``fogbayes --help`` and commands that fit nothing do
not need it. If JAX is already imported the switch is flipped now; otherwise the
environment variable is set, which JAX reads when it is first imported. Child processes
inherit that variable: JAX programs they run are float64 too (as fogbayes' own Dask
workers need).

Compiled programs are kept on disk (JAX's persistent compilation cache), so a second
``fogbayes loop`` on a record of the same size does not compile again: on the README's 1 h
record, 43.9 s the first time and 34.7 s the next (39 programs, 0.7 MB). They live under
:func:`fogbayes_cache_dir` ``/jax`` (beside the Numba loops' ``/numba``), capped at
:data:`CACHE_MAX_BYTES`, least recently used first out; programs that compiled in under
:data:`CACHE_MIN_SECONDS` are not worth a file. ``FOGBAYES_JAX_CACHE=off`` turns it off; a
folder the user set for JAX itself (``JAX_COMPILATION_CACHE_DIR``) is left as it is; an
unwritable folder turns it off rather than warn at every compilation.
"""

import os
import sys
from pathlib import Path

#: most bytes of compiled programs kept on disk
CACHE_MAX_BYTES = 1 << 30
#: programs compiled faster than this are not written (reading a file costs ~1 ms)
CACHE_MIN_SECONDS = 0.1


def fogbayes_cache_dir() -> Path:
    """The user's cache folder for fogbayes: ``$FOGBAYES_CACHE_DIR``, else
    ``$XDG_CACHE_HOME/fogbayes``, else ``~/.cache/fogbayes``."""
    if os.environ.get("FOGBAYES_CACHE_DIR"):
        return Path(os.environ["FOGBAYES_CACHE_DIR"])
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "fogbayes"


def jax_cache_dir() -> str | None:
    """Where compiled JAX programs are kept, or None (turned off, or not writable)."""
    if os.environ.get("FOGBAYES_JAX_CACHE", "").lower() in ("off", "0", "false", "no"):
        return None
    path = fogbayes_cache_dir() / "jax"
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError:
        return None
    return str(path) if os.access(path, os.W_OK) else None


#: environment variable naming the folder fogbayes itself gave JAX (children inherit JAX's
#: variable; this tells it apart from one the user set)
_OURS = "FOGBAYES_JAX_CACHE_SET"


def _settings() -> dict[str, object]:
    """JAX options fogbayes sets: float64 always; the compilation cache unless the user
    configured JAX's own (then left as it is) or turned ours off."""
    out: dict[str, object] = {"jax_enable_x64": True}
    given = os.environ.get("JAX_COMPILATION_CACHE_DIR")
    if given is not None and given != os.environ.get(_OURS):
        return out
    path = jax_cache_dir()  # this process's choice, not one inherited from a parent
    out["jax_compilation_cache_dir"] = path
    if path is not None:
        out["jax_persistent_cache_min_compile_time_secs"] = CACHE_MIN_SECONDS
        try:  # JAX keeps the cache under a size limit only with file locks
            import filelock  # noqa: F401
            out["jax_compilation_cache_max_size"] = CACHE_MAX_BYTES
        except ImportError:
            pass
    return out


def _apply(settings: dict[str, object]) -> None:
    jax = sys.modules.get("jax")
    for name, value in settings.items():
        if jax is not None:
            jax.config.update(name, value)
        elif value is None:  # read by JAX when it is first imported
            os.environ.pop(name.upper(), None)
        else:
            os.environ[name.upper()] = "true" if value is True else str(value)
    if settings.get("jax_compilation_cache_dir"):
        os.environ[_OURS] = os.environ["JAX_COMPILATION_CACHE_DIR"] = str(
            settings["jax_compilation_cache_dir"])
    elif "jax_compilation_cache_dir" in settings:
        os.environ.pop(_OURS, None)
        os.environ.pop("JAX_COMPILATION_CACHE_DIR", None)


_apply(_settings())
