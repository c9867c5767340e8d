"""What users call, timed as they see it: public functions and CLI commands end to end.

Every row is a ratio against the reference a user would otherwise run, measured in the same
run; absolute times are printed too. Rows:

* ``allan_deviation(y, 1, taus="octave")`` with its intervals (noise identification, EDF)
  vs allantools ``oadev`` on white noise, 2^20 and 1e7 samples; ``mdev`` and ``ohdev`` on
  2^20. In one process, warm (compilation paid once before), best of ``--repeat``;
* ``fogbayes allan FILE.npz --json`` on 1e6 samples in a fresh process vs a fresh-process
  script that loads the same file and runs allantools ``oadev`` (wall time: import, read,
  compilation, fit), with the compilation cache warm and empty;
* ``fogbayes fit REC -m thermal --json`` on the 6.3 h, 10 Hz chamber test (fresh process);
* ``fogbayes --help`` (fresh process; no JAX import);
* ``fogbayes loop`` on the README's 1 h demo record (fresh processes): with an empty cache
  folder, again with the programs the first run kept (JAX and Numba), and with the JAX
  program cache off (``FOGBAYES_JAX_CACHE=off``; the Numba loops still cached), as before
  JAX's programs were kept; median of ``--repeat`` rounds, each from a new empty folder.

Run: ``python benchmarks/bench_public.py [--repeat 3] [--quick] [--only functions|cli|loop]``.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from _timing import best_of


def _wall(cmd: list[str], repeat: int, env: dict | None = None) -> float:
    def run():
        subprocess.run(cmd, check=True, capture_output=True, env=env)
    return best_of(run, repeat)


def _cold(cmd: list[str]) -> float:
    """Wall time with an empty compilation cache (Numba compiles every loop it runs)."""
    import os

    with tempfile.TemporaryDirectory() as cache:
        env = {**os.environ, "FOGBAYES_CACHE_DIR": cache}
        t0 = time.perf_counter()
        subprocess.run(cmd, check=True, capture_output=True, env=env)
        return time.perf_counter() - t0


def bench_functions(repeat: int, sizes) -> None:
    import allantools

    from fogbayes.stats.allan import allan_deviation

    refs = {"oadev": allantools.oadev, "mdev": allantools.mdev, "ohdev": allantools.ohdev}
    print("| call | samples | fogbayes (s) | allantools (s) | ratio |")
    print("| --- | --- | --- | --- | --- |")
    for n in sizes:
        y = np.random.default_rng(0).standard_normal(n)
        for kind in ("oadev", "mdev", "ohdev") if n <= 1 << 20 else ("oadev",):
            allan_deviation(y, 1.0, taus="octave", kind=kind)  # compile for this shape
            a = best_of(lambda: allan_deviation(y, 1.0, taus="octave", kind=kind), repeat)
            b = best_of(lambda: refs[kind](y, rate=1.0, data_type="freq", taus="octave"), repeat)
            print(f"| allan_deviation kind={kind} (intervals) | {n} | {a:.3f} | {b:.3f} | "
                  f"{b / a:.2f} |")


def bench_cli(repeat: int, quick: bool) -> None:
    import fogbayes
    from fogbayes.simulate import simulate

    exe = [sys.executable, "-m", "fogbayes", "-q"]
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        n = 100_000 if quick else 1_000_000
        static = simulate("static", seed=1, duration=n / 10.0, fs=10.0).recording
        fogbayes.save(static, tmp / "static.npz")
        script = tmp / "plain_allantools.py"
        script.write_text("import numpy as np, allantools\n"
                          f"z = np.load('{tmp / 'static.npz'}')\n"
                          "allantools.oadev(z['output'], rate=10.0, data_type='freq', "
                          "taus='octave')\n")
        allan_cmd = exe + ["allan", str(tmp / "static.npz"), "--json", str(tmp / "a.json")]
        cold = _cold(allan_cmd)
        cli = _wall(allan_cmd, repeat)
        ref = _wall([sys.executable, str(script)], repeat)
        print("| command (fresh process) | fogbayes (s) | reference (s) | fogbayes / reference |")
        print("| --- | --- | --- | --- |")
        print(f"| fogbayes allan, {n} samples NPZ | {cli:.2f} | {ref:.2f} (load + allantools "
              f"oadev script) | {cli / ref:.2f} |")
        print(f"| fogbayes allan, {n} samples NPZ, empty compilation cache | {cold:.2f} | "
              f"{ref:.2f} | {cold / ref:.2f} |")
        dur, fs = (3600.0, 1.0) if quick else (None, None)
        chamber = simulate("thermal", seed=0, duration=dur, fs=fs).recording
        fogbayes.save(chamber, tmp / "chamber.csv")
        fit = _wall(exe + ["fit", str(tmp / "chamber.csv"), "-m", "thermal", "--json",
                           str(tmp / "f.json")], repeat)
        print(f"| fogbayes fit -m thermal, {chamber.n} samples CSV | {fit:.2f} | | |")
        helps = _wall(exe[:-1] + ["--help"], repeat)
        print(f"| fogbayes --help | {helps:.2f} | | |")


def bench_loop_cli(repeat: int) -> None:
    """``fogbayes loop`` end to end: empty cache, warm cache, JAX program cache off.

    Each of ``repeat`` rounds starts from a new, empty cache folder and runs the three in
    that order; the table gives the median seconds and the median of the rounds' ratios
    (a ratio within one round is steadier than across rounds on a shared box)."""
    import os

    rounds = []
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        base = {k: v for k, v in os.environ.items()
                if not k.startswith(("JAX_COMPILATION_CACHE", "FOGBAYES_JAX_CACHE"))}
        exe = [sys.executable, "-m", "fogbayes", "-q"]
        subprocess.run(exe + ["demo", "--out", str(tmp / "demo"), "--duration", "3600",
                              "--fs", "1"], check=True, capture_output=True,
                       env={**base, "FOGBAYES_CACHE_DIR": str(tmp / "demo_cache")})
        cmd = exe + ["loop", str(tmp / "demo" / "demo_recording.csv"), "--model", "bias-t",
                     "--json", str(tmp / "loop.json"), "--compensated", str(tmp / "loop.csv")]

        def once(env: dict) -> float:
            t0 = time.perf_counter()
            subprocess.run(cmd, check=True, capture_output=True, env=env)
            return time.perf_counter() - t0

        for k in range(max(repeat, 1)):  # the demo's own programs do not count: new folder
            env = {**base, "FOGBAYES_CACHE_DIR": str(tmp / f"cache{k}")}
            rounds.append((once(env), once(env), once({**env, "FOGBAYES_JAX_CACHE": "off"})))
    cold, warm, off = (np.array(col) for col in zip(*rounds))
    print(f"| fogbayes loop, 1 h demo record (fresh process; median of {len(rounds)} rounds) "
          "| seconds | / empty cache |")
    print("| --- | --- | --- |")
    print(f"| empty cache folder | {np.median(cold):.1f} | 1.00 |")
    print(f"| programs kept by the run above | {np.median(warm):.1f} "
          f"| {np.median(warm / cold):.2f} |")
    print(f"| JAX program cache off (Numba loops cached) | {np.median(off):.1f} "
          f"| {np.median(off / cold):.2f} |")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--quick", action="store_true", help="small sizes (a smoke run)")
    ap.add_argument("--only", choices=("functions", "cli", "loop"), help="one group of rows")
    args = ap.parse_args()
    t0 = time.time()
    if args.only in (None, "functions"):
        bench_functions(args.repeat, (1 << 14,) if args.quick else (1 << 20, 10_000_000))
        print()
    if args.only in (None, "cli"):
        bench_cli(args.repeat, args.quick)
        print()
    if args.only in (None, "loop"):
        bench_loop_cli(args.repeat)
    print(f"\n({time.time() - t0:.0f} s in all)")


if __name__ == "__main__":
    main()
