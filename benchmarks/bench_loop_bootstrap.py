"""The loop on records whose evidence needs the Bartlett bootstrap, as a user runs it.

    python benchmarks/bench_loop_bootstrap.py [--trees DIR ...] [--repeat 1] [--json F]

Each record is ``fogbayes.loop.run_loop`` in a fresh process (imports and compilation
counted; the CLI adds reading a CSV and writing documents). The records are the CI-sized
cases of ``tests/test_loop_effects.py`` (3 h at 1 Hz, 900 blocks, 200 null simulations):

* ``walk``: a clean record with random-walk noise on paper 004's programme (seed 4): the
  refitted drift leaves the walk mode, so its ratio's null scale is bootstrapped until the
  decision is settled (up to 100 series, two refits each);
* ``cubic``: a cubic temperature law under a quadratic base (seed 8, 3x the default);
* ``step``: a mid-record step (seed 1, 2x): one batch of 5 series settles it.

``--trees`` runs the same records with other source trees first on ``sys.path`` (e.g. a
``git worktree`` of an older commit) in the same run, so that the ratio is measured on the
same box under the same load. Reported: wall time per record and tree, the effects found
and the final 10 s RMS (equal across trees up to rounding when only speed changed).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

CASES = {
    "walk": dict(effect=None, seed=4, noise="walk", profile="paper004"),
    "cubic": dict(effect="temperature_order", seed=8, magnitude=3.0),
    "step": dict(effect="step", seed=1, magnitude=2.0),
}

ONE = """
import json, sys, time
case = json.loads(sys.argv[1])
import fogbayes
from fogbayes.loop import run_loop
from fogbayes.loop.testbed import make_record
effect, seed = case.pop("effect"), case.pop("seed")
rec = make_record(effect, seed=seed, duration=10800.0, fs=1.0, **case).recording
t0 = time.perf_counter()
res = run_loop(rec, "bias-t", seed=seed, max_steps=1, n_sims=200, target_blocks=900)
print(json.dumps({"seconds": time.perf_counter() - t0, "effects": res.effects,
                  "final_rms": res.final.rms, "fogbayes": fogbayes.__file__}))
"""


def run_case(tree: Path, case: dict) -> dict:
    # the tree first; keep what the caller had on the path (packages installed beside it)
    path = os.pathsep.join(p for p in (str(tree), os.environ.get("PYTHONPATH", "")) if p)
    env = {**os.environ, "PYTHONPATH": path, "MPLBACKEND": "Agg"}
    out = subprocess.run([sys.executable, "-c", ONE, json.dumps(case)], env=env, cwd=tree,
                         capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trees", nargs="*", default=[], help="other source trees to compare")
    ap.add_argument("--cases", nargs="*", default=list(CASES))
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--json", default=None)
    args = ap.parse_args(argv)
    trees = [ROOT] + [Path(t).resolve() for t in args.trees]
    rows = []
    for name in args.cases:
        for _ in range(args.repeat):
            for tree in trees:
                r = run_case(tree, dict(CASES[name]))
                r.update(case=name, tree=str(tree))
                rows.append(r)
                print(f"{name:6s} {tree.name:12s} {r['seconds']:7.1f} s  {r['effects']} "
                      f"rms {r['final_rms']:.6g}", flush=True)
    if args.json:
        Path(args.json).write_text(json.dumps({"machine": platform.processor() or platform.machine(),
                                               "cpus": os.cpu_count(), "rows": rows}, indent=1))


if __name__ == "__main__":
    main()
