"""Are one unit's bias-law standard errors right? z-scores of simulated units (issue #26).

    python benchmarks/pool_thermal_units.py --units 60 --flicker-span 4 [--bank-span 2]

Each unit: the 1 h, 1 Hz generic chamber test of ``bench_pool_thermal.py`` (bias law
a0 + a1 (T - 20) + a2 (T - 20)^2 drawn from that script's population), with the thermal
scenario's noise N 0.005, B 0.02, K 0.02 added here so that the flicker can be drawn over
``--flicker-span`` x the record and its first part kept: 1 is the simulator's own flicker
(FFT over exactly the record: periodic, no power below 1/T), 4 is flicker with power down
to 1/(4T), as a real gyro's. Each unit is fitted as :func:`fogbayes.pool.thermal.fit_unit`
fits it (GLS, covariance under the REML noise), optionally with the flicker bank reaching
``--bank-span`` x the record (default 2, the loop's); or, with ``--estimator published``, as
the loop publishes it (:func:`fogbayes.loop.estimator.publish`: GLS under the noise less the
walk, the IEEE constant, the sandwich covariance under the full ML noise), or
``published-reml`` (the same with the full noise's hyperparameters and s2 by REML,
:func:`fogbayes.loop.estimator.reml_noise`: what ``fogbayes loop`` publishes). Printed: the sd of
z = (estimate - truth) / se per coefficient (1 when the standard errors are right) and the
coverage of the units' 90 % intervals.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from concurrent.futures import ProcessPoolExecutor

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

MU = np.array([0.5, 0.01, 2e-4])
SD = np.array([0.02, 5e-4, 2e-5])


def unit(job: tuple[int, int, float]) -> list[float]:
    import dataclasses

    from fogbayes.loop.context import make_context
    from fogbayes.loop.fitting import fit_terms
    from fogbayes.loop.reml import reml_theta
    from fogbayes.inference import noise_ssm as ns
    from fogbayes.loop.bases import base_terms
    from fogbayes.models.polynomial import PolyBasis, rebase_matrix
    from fogbayes.simulate import simulate
    from fogbayes.simulate.noise import flicker_noise, random_walk_noise, white_noise

    seed, span, bank, estimator = job
    truth = MU + SD * np.random.default_rng(seed).standard_normal(3)
    rec = simulate("thermal", seed=777_000 + seed, duration=3600.0, fs=1.0, noise={},
                   effects={"temperature_order": {"coeffs": list(truth), "T_ref": 20.0}}
                   ).recording
    n, s = rec.n, 777_000 + seed
    noise = (white_noise(n, 1.0, seed=s, N=0.005) + random_walk_noise(n, 1.0, seed=s, K=0.02)
             + flicker_noise(span * n, 1.0, seed=s, B=0.02, span=1)[:n])
    ctx = make_context(dataclasses.replace(rec, output=np.asarray(rec.output) + noise))
    terms = base_terms(ctx, "bias-t", "2")
    fit = fit_terms(ctx, terms, spec=ns.make_spec(ctx.grid.dt, ctx.cov.duration,
                                                  span=(0.5, bank)))
    th = reml_theta(fit.noise, ctx.y, fit.X, ctx.grid.mask, ctx.grid.w)
    r = ns.gls(fit.noise.spec, th, ctx.y, fit.X, ctx.grid.mask, ctx.grid.w)
    n_obs, p = float(np.sum(ctx.grid.mask > 0)), fit.X.shape[1]
    beta, cov = np.asarray(r.beta), np.asarray(r.cov_beta) * n_obs / (n_obs - p)
    if estimator != "reml-gls":
        from fogbayes.loop.estimator import publish, reml_noise

        cn = reml_noise(ctx, fit) if estimator == "published-reml" else None
        pub = publish(ctx, fit, cov_noise=cn).noise
        beta, cov = np.asarray(pub.beta), np.asarray(pub.cov_beta)
    pp = terms[1].params
    M = rebase_matrix(PolyBasis(("T",), tuple((k,) for k in range(3)), (float(pp["centre"]),),
                                (float(pp["scale"]),)), origin=[20.0], unit=[1.0])
    return ((M @ beta - truth) / np.sqrt(np.diag(M @ cov @ M.T))).tolist()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--units", type=int, default=60)
    ap.add_argument("--first-seed", type=int, default=0,
                    help="units are seeds first-seed .. first-seed+units-1 (a fresh set: "
                         "report on seeds the estimator was not chosen on)")
    ap.add_argument("--flicker-span", type=int, default=4)
    ap.add_argument("--bank-span", type=float, default=2.0)
    ap.add_argument("--estimator", default="reml-gls",
                    choices=("reml-gls", "published", "published-reml"))
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--out", default=None)
    a = ap.parse_args()
    with ProcessPoolExecutor(a.workers) as ex:
        z = np.array(list(ex.map(unit, [(s, a.flicker_span, a.bank_span, a.estimator)
                                        for s in range(a.first_seed,
                                                       a.first_seed + a.units)])))
    print(f"{a.units} units (seeds {a.first_seed}+), flicker over {a.flicker_span} x the record, bank to "
          f"{a.bank_span:g} x, {a.estimator}: z sd a0/a1/a2 {np.round(z.std(0, ddof=1), 3).tolist()}, "
          f"90 % coverage {np.round((np.abs(z) < 1.645).mean(0), 3).tolist()}")
    if a.out:
        json.dump({"args": vars(a), "z": z.tolist()}, open(a.out, "w"))


if __name__ == "__main__":
    main()
