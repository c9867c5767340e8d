"""`fogbayes fit -m bias-t` (least squares, paper 004) against `fogbayes loop -m bias-t
--max-steps 0` (= `fit --estimator gls`: GLS under the loop's noise model), on the README
tour's record and on others simulated the same way.

For each seed, the record of `fogbayes demo --seed S --duration 3600 --fs 1` (a thermal
chamber test with a temperature-rate term that neither bias-t calibration has) and, beside
it, the same test without that term (`simulate("thermal")`, where a cubic in T can hold the
bias). Each calibration compensates its own record; printed per scenario: the RMS difference
of the two compensated outputs over the output's sd, and each calibration's error against
the simulation's truth, RMS over the record of (true bias - fitted bias), the mean kept.

Run: ``python benchmarks/estimators_tour.py [--seeds 0-9]`` (seed 0 is the tour's record).
"""

from __future__ import annotations

import argparse

import numpy as np


def _seeds(text: str) -> list[int]:
    lo, _, hi = text.partition("-")
    return list(range(int(lo), int(hi or lo) + 1))


def one(seed: int, rate_term: bool) -> tuple[float, float, float]:
    from fogbayes.effects.temperature_rate import TemperatureRate
    from fogbayes.loop.calibration import apply_calibration
    from fogbayes.loop.core import run_loop
    from fogbayes.simulate import simulate
    from fogbayes.thermal.workflow import compensate_recording, fit_recording

    effects = {TemperatureRate.name: {}} if rate_term else None
    sim = simulate("thermal", seed=seed, duration=3600.0, fs=1.0, effects=effects)
    rec = sim.recording
    y = np.asarray(rec.rate("deg/h"), float)
    truth = np.asarray(sim.truth.deterministic, float)
    ols = np.asarray(compensate_recording(rec, fit_recording(rec, model="bias-t"))["output"])
    doc = run_loop(rec, "bias-t", max_steps=0, seed=0).to_json()
    gls = np.asarray(apply_calibration(doc, rec).columns["output"])
    err = [float(np.sqrt(np.mean((truth - (y - c)) ** 2))) for c in (ols, gls)]
    return float(np.sqrt(np.mean((ols - gls) ** 2)) / np.std(ols)), err[0], err[1]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", default="0", help="seeds, e.g. 0 or 0-9")
    args = ap.parse_args()
    for rate_term, name in ((True, "tour (temperature-rate term planted)"),
                            (False, "thermal, no rate term")):
        print(f"{name}:")
        print("  seed  |ols-gls| / sd   error OLS   error GLS  (deg/h, RMS vs truth)")
        rows = []
        for s in _seeds(args.seeds):
            d, e_ols, e_gls = one(s, rate_term)
            rows.append((d, e_ols, e_gls))
            print(f"  {s:4d}  {d:14.3f}  {e_ols:10.4f}  {e_gls:10.4f}")
        r = np.array(rows)
        print(f"  GLS closer to the truth on {int(np.sum(r[:, 2] < r[:, 1]))} of {len(r)}; "
              f"median error ratio GLS / OLS {np.median(r[:, 2] / r[:, 1]):.3f}")


if __name__ == "__main__":
    main()
