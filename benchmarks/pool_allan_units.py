"""Why pooled N is worse than each unit's own N on the simulated fleets (RESULTS_pool.md).

    python benchmarks/pool_allan_units.py [--reps 10] [--json OUT]

The fleets of ``bench_pool.py`` (same seeds, 20 units, 3.6 h at 10 Hz): every unit fitted
alone (GLS, five terms). Then, with the population known (the simulator's medians and
spreads), each unit's shrunk estimate ``mu + S (S + Sigma_u)^-1 (y_u - mu)`` -- the mean of
the pool's per-unit posterior with the population fixed at the truth, so no sampler noise --
for three choices of the unit covariance Sigma_u:

* ``marginal``: what ``fogbayes.pool`` uses: the GLS log-space covariance of N, B, K, with
  the cross-covariances of a censored (unresolved) term dropped;
* ``conditional``: the resolved terms' covariance conditioned on the censored ones;
* ``diagonal``: the variances alone;
* ``conditional on Q-R too``: conditioned on every unresolved term of the five-term fit,
  the unpooled Q and R included;
* ``the same at the population``: as the previous, with the covariance evaluated where the
  population median puts N, B, K (:func:`fogbayes.pool.allan.at_population`, what the
  pool's second pass uses), here the simulator's medians.

Printed: RMS log error of N, B, K per choice, for all units and for the units whose K is
censored, and the units with the widest N intervals against their actual N error.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import bench_pool as bp  # noqa: E402  (the fleets, the same seeds)
from fogbayes.pool.allan import TERMS as ALL  # noqa: E402
from fogbayes.pool.allan import at_population, resolved_covariance  # noqa: E402

NBK = ("N", "B", "K")


def fleet_fits(reps: int):
    idx = [ALL.index(t) for t in NBK]
    Y, C, T, cens, full, at_pop = [], [], [], [], [], []
    for rep in range(reps):
        rng = np.random.default_rng(10_000 + rep)
        truths = [bp.unit_truth(rng) for _ in range(20)]
        for u, tr in enumerate(truths):
            f = bp.fit_record(bp.simulate(tr, 2 ** 17, seed=100_000 * rep + u), f"u{u}")
            Y.append(f.logp[idx])
            C.append(f.cov[np.ix_(idx, idx)])
            T.append(np.log([tr[t] for t in NBK]))
            cens.append([f.terms[t].low <= 0 for t in NBK])
            # every term's covariance and resolution (Q and R too: not pooled, but N trades
            # with Q at short taus)
            full.append((f.cov, np.array([f.terms[t].low <= 0 for t in ALL])))
            at_pop.append(resolved_covariance(at_population([f], NBK, bp.POP)[0])[np.ix_(idx, idx)])
    return np.array(Y), np.array(C), np.array(T), np.array(cens), full, np.array(at_pop)


def conditional_on_all(cov5, cen5):
    """N, B, K covariance conditioned on every unresolved term of the five-term fit; an
    unresolved pooled term keeps its own variance, without cross-covariances."""
    idx = [ALL.index(t) for t in NBK]
    r = ~cen5
    out = cov5.copy()
    if cen5.any():
        crc = cov5[np.ix_(r, cen5)]
        out[np.ix_(r, r)] = cov5[np.ix_(r, r)] - crc @ np.linalg.solve(cov5[np.ix_(cen5, cen5)], crc.T)
        out[np.ix_(r, cen5)] = 0.0
        out[np.ix_(cen5, r)] = 0.0
    return out[np.ix_(idx, idx)]


def covariance(c, cen, how):
    r = ~cen
    if how == "diagonal":
        return np.diag(np.diag(c))
    if how == "marginal" or not cen.any():
        return c * np.outer(r, r) + np.diag(np.where(cen, np.diag(c), 0.0))
    out = np.diag(np.where(cen, np.diag(c), 0.0))
    crc = c[np.ix_(r, cen)]
    out[np.ix_(r, r)] = c[np.ix_(r, r)] - crc @ np.linalg.solve(c[np.ix_(cen, cen)], crc.T)
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--reps", type=int, default=10)
    ap.add_argument("--json", default=None)
    args = ap.parse_args(argv)
    Y, C, T, cens, full, C_pop = fleet_fits(args.reps)
    C_all = np.array([conditional_on_all(c5, k5) for c5, k5 in full])
    mu = np.log([bp.POP[t] for t in NBK])
    S = np.diag(np.array([bp.SPREAD[t] for t in NBK]) ** 2)
    out = {"reps": args.reps, "units": len(Y), "censored": dict(zip(NBK, cens.sum(0).tolist())),
           "rms": {}}
    for group, mask in (("all", np.ones(len(Y), bool)), ("K censored", cens[:, 2])):
        rows = {"single": Y[mask]}
        for how in ("marginal", "conditional", "diagonal"):
            rows[how] = np.array([mu + S @ np.linalg.solve(S + covariance(c, cen, how), y - mu)
                                  for y, c, cen in zip(Y[mask], C[mask], cens[mask])])
        rows["conditional on Q-R too"] = np.array(
            [mu + S @ np.linalg.solve(S + c, y - mu) for y, c in zip(Y[mask], C_all[mask])])
        rows["the same at the population"] = np.array(
            [mu + S @ np.linalg.solve(S + c, y - mu) for y, c in zip(Y[mask], C_pop[mask])])
        for how, est in rows.items():
            rms = np.sqrt(np.mean((est - T[mask]) ** 2, axis=0))
            out["rms"][f"{group}: {how}"] = dict(zip(NBK, rms.round(4).tolist()))
            print(f"{group:10s} {how:22s} RMS log error N {rms[0]:.4f} B {rms[1]:.4f} "
                  f"K {rms[2]:.4f}  ({mask.sum()} units)")
    for name, cov in (("marginal", C), ("conditional on Q-R too", C_all),
                      ("the same at the population", C_pop)):
        z = (Y - T) / np.sqrt(np.diagonal(cov, axis1=1, axis2=2))
        res = ~cens
        zr = [float(np.sqrt(np.mean(z[res[:, j], j] ** 2))) for j in range(3)]
        out[f"rms_z_resolved: {name}"] = dict(zip(NBK, np.round(zr, 3).tolist()))
        print(f"RMS of error / sd over resolved terms, {name}: N {zr[0]:.2f} B {zr[1]:.2f} "
              f"K {zr[2]:.2f} (1 for calibrated sds)")
    sd = np.sqrt(np.diagonal(C, axis1=1, axis2=2))
    wide = np.argsort(-sd[:, 0])[:5]
    out["widest_N"] = [{"unit": int(i), "sd_log": sd[i].round(3).tolist(),
                        "censored": cens[i].tolist(), "error_log": (Y - T)[i].round(3).tolist()}
                       for i in wide]
    for w in out["widest_N"]:
        print("widest N interval:", w)
    if args.json:
        Path(args.json).write_text(json.dumps(out, indent=1) + "\n")


if __name__ == "__main__":
    main()
