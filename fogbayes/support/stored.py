"""Programs kept on disk as exported StableHLO (``jax.export``), so that a new process need
not trace them again.

JAX's persistent cache (:mod:`fogbayes._config`) keeps compiled code keyed by the lowered
module: a new process still traces and lowers a program before it can look its code up. For
the NUTS samplers (NumPyro's tree builder, the potential's gradient, the Laplace Hessian)
that is seconds of every warm command. :func:`stored` exports a program once, writes it under
``<cache folder>/exported/``, and in later processes calls the stored module, whose compiled
code the persistent cache then holds.

An entry is keyed by the caller's ``key`` (everything the function closes over that is not an
argument), the arguments' tree, shapes and dtypes, and a fingerprint of fogbayes's sources and
of the JAX, jaxlib and NumPyro versions: any change of code makes new entries (a closure value
left out of ``key`` is the one way to a stale program). ``FOGBAYES_JAX_CACHE=off`` turns
stored programs off with the compile cache.
"""

from __future__ import annotations

import functools
import hashlib
import os
import threading
from importlib.util import find_spec
from pathlib import Path

from .lazy import lazy_module
from .programs import program

jax = lazy_module("jax")

#: most stored programs kept (each ~30-100 kB); past it the least recently written go
MAX_ENTRIES = 500


@functools.lru_cache(maxsize=1)
def fingerprint() -> str:
    """sha256 of fogbayes's Python sources (~270 files, ~20 ms) and the versions of the
    libraries that trace and lower its programs."""
    import jaxlib
    import numpyro

    h = hashlib.sha256(f"{jax.__version__}|{jaxlib.__version__}|{numpyro.__version__}|"
                       f"{jax.config.jax_enable_x64}".encode())
    root = Path(__file__).resolve().parents[1]
    for path in sorted(root.rglob("*.py")):
        h.update(str(path.relative_to(root)).encode())
        h.update(path.read_bytes())
    return h.hexdigest()


def stored_folder() -> Path | None:
    """Where exported programs are kept: beside JAX's compiled code, or None where that cache
    is off (:func:`fogbayes._config.jax_cache_dir`)."""
    from .._config import jax_cache_dir

    folder = jax_cache_dir()
    return None if folder is None else Path(folder) / "exported"


def stored(fun, key: tuple, *, platform: str = "cpu", compiler_options: dict | None = None):
    """``fun`` as a compiled function whose traced program is kept on disk (module doc).

    ``key``: a tuple of plain values naming everything ``fun`` depends on besides its
    arguments (a sampler's lengths, target acceptance, model variant). ``platform``: the one
    the stored module runs on (the samplers run on the CPU:
    :func:`fogbayes.inference.nuts.on_host`). ``compiler_options``: XLA's, for compiling it
    (``jax.jit``'s argument; the stored module does not depend on them, JAX's compile cache
    keys by them).
    Where the cache is off, or an argument tree cannot be serialised, it is ``program(fun)``.
    """
    traced = program(fun, compiler_options=compiler_options)
    calls: dict = {}
    lock = threading.Lock()  # chains in threads make their first calls together: one export

    def call(*args):
        leaves, tree = jax.tree_util.tree_flatten(args)
        specs = tuple(jax.ShapeDtypeStruct(jax.numpy.shape(a), jax.numpy.result_type(a))
                      for a in leaves)
        sig = (str(tree), tuple((s.shape, str(s.dtype)) for s in specs))
        fast = calls.get(sig)
        if fast is None:
            with lock:
                fast = calls.get(sig)
                if fast is None:
                    fast = calls[sig] = _load_or_export(traced, key, sig, tree, specs, platform,
                                                        compiler_options)
        return fast(*args)

    return call


def _load_or_export(traced, key, sig, tree, specs, platform, compiler_options):
    """The stored program for these arguments: read, or exported and written; ``traced``
    itself where nothing can be stored."""
    folder = stored_folder()
    if folder is None or find_spec("flatbuffers") is None:  # jax.export serialises with it
        return traced
    name = hashlib.sha256(repr((key, sig, platform, fingerprint())).encode()).hexdigest()
    path = folder / f"{name}.jaxexport"
    _register_namedtuples(tree)  # before reading: the stored tree names them
    exported = None
    if path.exists() and _lapack_ready():
        try:
            exported = jax.export.deserialize(bytearray(path.read_bytes()))
        except Exception:  # a truncated or foreign file: export again and replace it
            exported = None
    if exported is None:
        args = jax.tree_util.tree_unflatten(tree, specs)
        exported = jax.export.export(traced.jitted, platforms=(platform,))(*args)
        _register_namedtuples(exported.out_tree)
        try:
            blob = exported.serialize()
        except Exception:  # a tree JAX cannot serialise (a custom node): trace each time
            return traced
        _write_atomically(path, blob)
    return program(exported.call, compiler_options=compiler_options)


def _write_atomically(path: Path, blob: bytes) -> None:
    """Write to a temporary name and rename: a process reading at the same time sees the
    whole file or none (a failed write only loses the speed-up). Then keep the newest
    :data:`MAX_ENTRIES` (each change of fogbayes's sources makes new entries)."""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_name(f"{path.name}.{os.getpid()}.tmp")
        tmp.write_bytes(blob)
        os.replace(tmp, path)
        entries = sorted(path.parent.glob("*.jaxexport"), key=lambda p: p.stat().st_mtime)
        for old in entries[: max(0, len(entries) - MAX_ENTRIES)]:
            old.unlink(missing_ok=True)
    except OSError:  # another process pruning at the same time, a full disk: harmless
        pass


@functools.lru_cache(maxsize=1)
def _lapack_ready() -> bool:
    """jaxlib loads its LAPACK kernels when JAX first lowers a linear-algebra operation; a
    stored module is not lowered again, and its Cholesky or eigh then called null pointers
    (a segmentation fault in a fresh process, jax 0.9.2). Load them as that lowering does;
    False (use the traced program) where jaxlib offers no such call."""
    try:
        import numpy as np
        from jaxlib import lapack

        lapack.prepare_lapack_call("potrf_ffi", np.dtype("float64"))
        return True
    except Exception:
        return False


_registered: set = set()


def _register_namedtuples(treedef) -> None:
    """Name every namedtuple type in ``treedef`` for ``jax.export``'s serialisation (it
    stores trees by type name, and refuses types it was not told of)."""
    data = treedef.node_data()
    if data is not None:
        kind = data[0]
        if (isinstance(kind, type) and issubclass(kind, tuple) and hasattr(kind, "_fields")
                and kind not in _registered):
            try:
                jax.export.register_namedtuple_serialization(
                    kind, serialized_name=f"{kind.__module__}.{kind.__qualname__}")
            except ValueError:  # registered already, by its own module
                pass
            _registered.add(kind)
    for child in treedef.children():
        _register_namedtuples(child)
