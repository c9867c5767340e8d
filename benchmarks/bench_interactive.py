"""The commands users run most, in fresh processes, as ratios to a plain pandas + NumPy script.

Every row of issue 56's table is measured in one run against ``plain_cubic.py`` (reads the
README tour's 1 h, 1 Hz record, fits a cubic in T by least squares, writes the compensated
CSV). The box's speed drifts within minutes (the script's best of three took 0.43 s and
0.64 s twenty minutes apart), so each row's ratio is to the script's best of the calls
interleaved with that row's warm calls, not to one figure from the run's start:

* ``fogbayes fit REC -m bias-t``, ``fogbayes loop REC -m bias-t``,
  ``fogbayes fit REC -m thermal --bayes`` on that record;
* ``fogbayes fit P000 -m composite`` on ``fogbayes simulate paper000``;
* ``fogbayes pool UNITS/`` on four 1 h, 10 Hz ``fogbayes simulate static`` records
  (seeds 11..14), and ``fogbayes allan STATIC --bayes`` on the first of them.

Cold is one call with an empty cache folder (``FOGBAYES_CACHE_DIR``, JAX programs and Numba
loops); warm is the best of ``--repeat`` calls after that call filled the folder. The peak
resident memory (``getrusage`` of the child) of ``fogbayes loop`` on the demo's 6.3 h,
10 Hz record is measured in a process of its own, with an empty cache folder. The load
average at the start and end is printed: on a busy machine the ratios are upper bounds.

Run: ``python benchmarks/bench_interactive.py [--repeat 2] [--no-memory] [--only NAME,...]``.
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
FOG = [sys.executable, "-m", "fogbayes", "-q"]

# name, argv after "fogbayes -q" ({rec}, {p000}, {units}, {static}, {out} substituted), target
ROWS = [
    ("fit bias-t", ["fit", "{rec}", "-m", "bias-t", "--json", "{out}"], 2.0),
    ("loop bias-t", ["loop", "{rec}", "-m", "bias-t", "--json", "{out}"], 10.0),
    ("fit thermal --bayes", ["fit", "{rec}", "-m", "thermal", "--bayes", "--json", "{out}"], 10.0),
    ("fit P000 composite", ["fit", "{p000}", "-m", "composite", "--json", "{out}"], 5.0),
    ("pool 4 static units", ["pool", "{units}", "--json", "{out}"], 10.0),
    ("allan STATIC --bayes", ["allan", "{static}", "--bayes", "--json", "{out}"], 15.0),
]


def _load() -> str:
    return " ".join(f"{x:.2f}" for x in os.getloadavg())


def _run(cmd: list[str], env: dict) -> float:
    t0 = time.perf_counter()
    r = subprocess.run(cmd, env=env, capture_output=True, text=True)
    dt = time.perf_counter() - t0
    if r.returncode != 0:
        raise SystemExit(f"failed ({r.returncode}): {' '.join(cmd)}\n{r.stderr[-2000:]}")
    return dt


def _inputs(tmp: Path, env: dict) -> dict:
    subprocess.run(FOG + ["demo", "--out", str(tmp / "demo1h"), "--duration", "3600", "--fs", "1"],
                   env=env, check=True, capture_output=True)
    subprocess.run(FOG + ["simulate", "paper000", "--out", str(tmp / "p000.csv")],
                   env=env, check=True, capture_output=True)
    (tmp / "units").mkdir()
    for seed in (11, 12, 13, 14):
        subprocess.run(FOG + ["simulate", "static", "--seed", str(seed), "--duration", "3600",
                              "--out", str(tmp / "units" / f"u{seed}.csv")],
                       env=env, check=True, capture_output=True)
    return {"rec": str(tmp / "demo1h" / "demo_recording.csv"), "p000": str(tmp / "p000.csv"),
            "units": str(tmp / "units"), "static": str(tmp / "units" / "u11.csv")}


def _peak_rss_mb(cmd: list[str], env: dict) -> tuple[float, float]:
    """Wall time and peak RSS (MB) of ``cmd`` run as the only child of a fresh Python."""
    probe = ("import resource, subprocess, sys, time, json; t0 = time.perf_counter(); "
             "subprocess.run(json.loads(sys.argv[1]), check=True, capture_output=True); "
             "dt = time.perf_counter() - t0; "
             "print(dt, resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024)")
    out = subprocess.run([sys.executable, "-c", probe, json.dumps(cmd)], env=env, check=True,
                         capture_output=True, text=True).stdout.split()
    return float(out[0]), float(out[1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeat", type=int, default=2, help="warm calls per row (best kept)")
    ap.add_argument("--no-memory", action="store_true", help="skip the 6.3 h loop memory row")
    ap.add_argument("--only", default="", help="comma-separated row names to run")
    ap.add_argument("--json", default="", help="also write the rows as JSON here")
    args = ap.parse_args()
    load0 = _load()
    rows = [r for r in ROWS if not args.only or r[0] in args.only.split(",")]
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        base = {**os.environ, "FOGBAYES_CACHE_DIR": str(tmp / "cache_inputs")}
        # as on a user's machine, where Python keeps the package's byte code: a sandbox's
        # PYTHONDONTWRITEBYTECODE made every call of an editable install compile its ~140
        # modules again (~0.2 s), while pandas and JAX in site-packages kept theirs
        base.pop("PYTHONDONTWRITEBYTECODE", None)
        paths = _inputs(tmp, base)
        plain_cmd = [sys.executable, str(HERE / "plain_cubic.py"), paths["rec"],
                     str(tmp / "plain.csv")]
        _run(plain_cmd, base)  # its first call reads the files into the page cache
        print(f"load average at start: {load0}")
        print(f"warm: best of {args.repeat}; plain: the script's best of {args.repeat + 1} "
              f"calls interleaved with them\n")
        print("| command | cold (s) | warm (s) | plain (s) | warm x plain | target | cold / warm |")
        print("| --- | --- | --- | --- | --- | --- | --- |")
        out = []
        for i, (name, argv, target) in enumerate(rows):
            env = {**base, "FOGBAYES_CACHE_DIR": str(tmp / f"cache{i}")}
            cmd = FOG + [a.format(**paths, out=str(tmp / f"out{i}.json")) for a in argv]
            cold = _run(cmd, env)
            plains, warms = [_run(plain_cmd, base)], []
            for _ in range(args.repeat):
                warms.append(_run(cmd, env))
                plains.append(_run(plain_cmd, base))
            warm, plain = min(warms), min(plains)
            shown = "fogbayes " + " ".join(argv).replace(" --json {out}", "").format(
                rec="REC", p000="P000", units="UNITS/", static="STATIC")
            print(f"| `{shown}` | {cold:.2f} | {warm:.2f} | {plain:.2f} | {warm / plain:.1f}x "
                  f"| <= {target:g}x | {cold / warm:.2f} |", flush=True)
            out.append({"row": name, "cold_s": cold, "warm_s": warm, "plain_s": plain,
                        "ratio": warm / plain, "target": target})
        mem = None
        if not args.no_memory:
            big = tmp / "demo63h.csv"
            subprocess.run(FOG + ["simulate", "thermal", "--effect", "temperature_rate",
                                  "--seed", "0", "--out", str(big)], env=base, check=True,
                           capture_output=True)
            env = {**base, "FOGBAYES_CACHE_DIR": str(tmp / "cache_mem")}
            cmd = FOG + ["loop", str(big), "-m", "bias-t", "--json", str(tmp / "big.json")]
            wall, mb = _peak_rss_mb(cmd, env)
            print(f"\n`fogbayes loop DEMO63H -m bias-t` (6.3 h, 10 Hz, empty cache): "
                  f"{wall:.1f} s, peak RSS {mb:.0f} MB (target < 500 MB)")
            mem = {"wall_s": wall, "peak_rss_mb": mb}
        load1 = _load()
        print(f"\nload average at end: {load1} ({os.cpu_count()} CPUs); "
              f"{datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC")
        if args.json:
            Path(args.json).write_text(json.dumps(
                {"rows": out, "loop_6h_memory": mem, "load_start": load0,
                 "load_end": load1}, indent=1) + "\n")


if __name__ == "__main__":
    main()
