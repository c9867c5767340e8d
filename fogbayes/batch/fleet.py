"""A fleet run: every recording of a folder through one task, then ``OUT/summary.json``.

``run_batch`` runs :func:`.jobs.run_one` on each file of :func:`.files.find_recordings` through
:func:`.engine.run_tasks` (or :func:`.vectorized.fit_vectorized`) and writes the summary, one
row per file in name order; a failing file is an ``error`` row, a run that cannot start raises
:class:`.files.FleetError`. Files are written atomically (:mod:`fogbayes.data.atomic`), the old
summary is removed first and the new one written last, and stale outputs of this run's
recordings are removed (``removed_stale``).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from functools import partial
from pathlib import Path

from .engine import check_engine, run_tasks
from .files import FleetError, check_task, find_recordings
from .jobs import (
    JobOptions,
    as_options,
    error_row,
    fit_outputs,
    load_one,
    output_names,
    run_one,
    write_json,
)


def run_batch(folder: str | Path, *, model: str, out: str | Path, task: str = "fit",
              engine: str = "local", address: str | None = None, workers: int = 2,
              pattern: str = "*.csv", vectorize: bool = False,
              options: JobOptions | dict | None = None, solver: str | None = None,
              on_done: Callable[[dict], None] | None = None) -> dict:
    """Run ``task`` on every recording of ``folder``; write and return the summary.

    ``on_done(row)`` is called as each recording finishes (e.g. to advance a progress bar).
    """
    import fogbayes

    check_task(task, model)
    check_engine(engine, address, workers)
    if vectorize and (engine != "local" or task not in ("fit", "compensate")):
        raise FleetError("--vectorize fits in this process (task fit or compensate)",
                         column="--vectorize",
                         fix="drop --engine dask/--address, use --task fit, or drop --vectorize")
    files = find_recordings(folder, pattern)
    opts = as_options(options)
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)

    def start() -> None:  # the work begins: the old summary no longer describes OUT
        (out / "summary.json").unlink(missing_ok=True)

    t0 = time.perf_counter()
    if vectorize:
        start()
        rows, n_workers = _vectorized(files, model, task, out, opts, solver, on_done), 1
    else:
        job = partial(run_one, model=model, task=task, out_dir=str(out), options=opts)
        done = run_tasks(job, [str(f) for f in files], engine=engine, address=address,
                         workers=workers, on_done=on_done, on_error=error_row, on_start=start)
        rows, n_workers = done["results"], done["workers"]
    _remove_stale(out, rows, files)
    n_ok = sum(r["status"] == "ok" for r in rows)
    summary = {"fogbayes_version": fogbayes.__version__, "task": task, "model": model,
               "engine": engine, "address": address, "workers": n_workers,
               "vectorized": bool(vectorize), "folder": str(folder), "pattern": pattern,
               "options": _options_json(opts), "n_files": len(rows), "n_ok": n_ok,
               "n_error": len(rows) - n_ok, "seconds": time.perf_counter() - t0, "rows": rows}
    write_json(summary, out / "summary.json")  # last: its presence means the run finished
    return summary


def _remove_stale(out: Path, rows: list[dict], inputs) -> None:
    """Remove each recording's outputs of an earlier run that this run did not write."""
    import os

    keep = set()
    for f in inputs:
        try:
            keep.add(Path(f).resolve())
        except OSError:
            pass
    for row in rows:
        written = set((row.get("outputs") or {}).values()) if row["status"] == "ok" else set()
        removed = []
        for name in output_names(Path(row["file"]).stem):
            p = out / name
            if name in written or not p.is_file() or p.resolve() in keep:
                continue
            try:
                os.remove(p)
            except FileNotFoundError:
                continue
            removed.append(name)
        if removed:
            row["removed_stale"] = removed


def _vectorized(files, model, task, out, opts: JobOptions, solver, on_done) -> list[dict]:
    """Load every file (a bad one is an error row), fit the rest in one batch, write each."""
    from .vectorized import fit_vectorized

    rows: dict[str, dict] = {}
    recs = {}
    for f in files:
        t = time.perf_counter()
        try:
            recs[str(f)] = load_one(f, opts)
        except Exception as exc:  # noqa: BLE001  one bad file never stops the fleet
            rows[str(f)] = {**error_row(f, exc), "seconds": time.perf_counter() - t}
            if on_done:
                on_done(rows[str(f)])
    names = list(recs)

    def failed(i: int, exc: Exception) -> None:  # this recording cannot be fitted: its row
        rows[names[i]] = {**error_row(names[i], exc), "seconds": 0.0}
        if on_done:
            on_done(rows[names[i]])

    t = time.perf_counter()
    docs = fit_vectorized(list(recs.values()), model=model, orders=opts.orders, bayes=opts.bayes,
                          seed=opts.seed, solver=solver, on_error=failed,
                          **(opts.fit_options or {}))
    share = (time.perf_counter() - t) / max(len(docs), 1)  # the batched stage, split evenly
    for (name, rec), doc in zip(recs.items(), docs):
        if doc is None:
            continue
        t = time.perf_counter()
        try:
            row = {"file": name, "status": "ok",
                   **fit_outputs(rec, Path(name), doc, task=task, out_dir=out)}
        except Exception as exc:  # noqa: BLE001
            row = error_row(name, exc)
        row["seconds"] = share + time.perf_counter() - t
        rows[name] = row
        if on_done:
            on_done(row)
    return [rows[str(f)] for f in files]


def _options_json(opts: JobOptions) -> dict:
    """The options for the summary: a calibration applied is named, not copied whole."""
    out = opts._asdict()
    if opts.params is not None:
        cal = opts.params.get("calibration") or {}
        out["params"] = {"schema": opts.params.get("schema"), "model": opts.params.get("model"),
                         "terms": [t.get("effect", "") + ":" + t.get("kind", "")
                                   for t in cal.get("terms", [])]} if cal else \
            {"schema": opts.params.get("schema"), "model": opts.params.get("model")}
    return out
