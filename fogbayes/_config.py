"""Numerical configuration applied when fogbayes is imported.

Turns on JAX float64 (``jax_enable_x64``; explicit float32 arrays stay float32) without
importing JAX (the environment variable, inherited by child processes). Enables JAX's persistent
compilation cache under :func:`fogbayes_cache_dir` ``/jax/<host>`` (:func:`host_tag`; capped at
:data:`CACHE_MAX_BYTES`, programs under :data:`CACHE_MIN_SECONDS` not stored) only where XLA's log
can be silenced (jax-ml/jax#38445); ``FOGBAYES_JAX_CACHE=off`` or ``TF_CPP_MIN_LOG_LEVEL`` < 3
turns it off; a user's own cache folder is left as it is.
"""

import os
import sys
import zlib
from importlib.util import find_spec
from pathlib import Path

#: most bytes of compiled programs kept on disk
CACHE_MAX_BYTES = 1 << 30
#: programs compiled faster than this are not written (reading a file costs ~1 ms)
CACHE_MIN_SECONDS = 0.1
#: XLA's C++ log level that hides the loader's false warnings (3: fatal messages only)
QUIET_LOG_LEVEL = 3
#: environment variable naming the folder fogbayes itself gave JAX (children inherit JAX's
#: variable; this tells it apart from one the user set)
_OURS = "FOGBAYES_JAX_CACHE_SET"


def fogbayes_cache_dir() -> Path:
    """The user's cache folder for fogbayes: ``$FOGBAYES_CACHE_DIR``, else
    ``$XDG_CACHE_HOME/fogbayes``, else ``~/.cache/fogbayes``."""
    if os.environ.get("FOGBAYES_CACHE_DIR"):
        return Path(os.environ["FOGBAYES_CACHE_DIR"])
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "fogbayes"


def host_tag() -> str:
    """8 hex digits naming this CPU: its architecture and, on Linux, its feature flags.

    (A checksum, not a secure hash: it only tells a user's few CPU types apart, and
    ``hashlib``/``platform`` would add ~9 ms to every import of fogbayes.)"""
    flags = ""
    try:
        with open("/proc/cpuinfo") as f:
            flags = next((line for line in f if line.startswith(("flags", "Features"))), "")
    except OSError:
        pass
    text = f"{os.uname().machine}|{' '.join(sorted(flags.split()))}"
    return f"{zlib.crc32(text.encode()):08x}"


def jax_cache_dir() -> str | None:
    """Where compiled JAX programs are kept, or None (turned off, or not writable)."""
    if os.environ.get("FOGBAYES_JAX_CACHE", "").lower() in ("off", "0", "false", "no"):
        return None
    path = fogbayes_cache_dir() / "jax" / host_tag()
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError:
        return None
    return str(path) if os.access(path, os.W_OK) else None


def _can_silence_xla() -> bool:
    """XLA's C++ log can be kept to fatal messages: the level is set already, or JAX is not
    imported yet and the user did not choose a level."""
    level = os.environ.get("TF_CPP_MIN_LOG_LEVEL")
    if level is None:
        return "jax" not in sys.modules
    return level.strip().isdigit() and int(level) >= QUIET_LOG_LEVEL


def _user_chose_jax_folder() -> bool:
    """JAX's cache folder was set by the user: by ``JAX_COMPILATION_CACHE_DIR``, or by
    ``jax.config.update("jax_compilation_cache_dir", ...)`` before fogbayes was imported
    (a folder fogbayes itself chose, named in :data:`_OURS`, does not count)."""
    ours = os.environ.get(_OURS)
    given = os.environ.get("JAX_COMPILATION_CACHE_DIR")
    if given is not None and given != ours:
        return True
    jax = sys.modules.get("jax")
    current = getattr(getattr(jax, "config", None), "jax_compilation_cache_dir", None)
    return current is not None and current != ours


def _settings() -> dict[str, object]:
    """JAX options fogbayes sets: float64 always; the compilation cache unless the user
    configured JAX's own (then left as it is), turned ours off or wants XLA's log."""
    out: dict[str, object] = {"jax_enable_x64": True}
    if _user_chose_jax_folder():
        return out
    path = jax_cache_dir() if _can_silence_xla() else None
    out["jax_compilation_cache_dir"] = path  # this process's choice, not its parent's
    if path is not None:
        out["jax_persistent_cache_min_compile_time_secs"] = CACHE_MIN_SECONDS
        if find_spec("filelock") is not None:  # JAX keeps a size limit only with file
            # locks; JAX imports it when it needs it (importing it here: ~50 ms per import)
            out["jax_compilation_cache_max_size"] = CACHE_MAX_BYTES
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
    path = settings.get("jax_compilation_cache_dir")
    if path:
        os.environ.setdefault("TF_CPP_MIN_LOG_LEVEL", str(QUIET_LOG_LEVEL))
        os.environ[_OURS] = os.environ["JAX_COMPILATION_CACHE_DIR"] = str(path)
    elif "jax_compilation_cache_dir" in settings:
        os.environ.pop(_OURS, None)
        os.environ.pop("JAX_COMPILATION_CACHE_DIR", None)


_apply(_settings())
