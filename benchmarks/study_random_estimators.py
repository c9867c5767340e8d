"""Which estimator should set the loop's calibration? The same terms, three estimators.

Usage::

    python benchmarks/study_random_estimators.py --seeds 2 13   # dev seeds of study_random

For each record of :mod:`study_random` (same draw, same measured noise) the loop runs as
the user calls it; its final terms are then refitted on the loop's blocks by

* what the loop publishes (:mod:`fogbayes.loop.estimator`: GLS under its noise model less
  the walk);
* GLS under the loop's noise model (white + flicker bank + random walk + Gauss-Markov);
* GLS under the same family without the random walk;
* least squares weighted by the blocks' sample counts;

each with the IEEE 952 constant (least squares has it by construction). ``--lpd`` prints
instead, for the base model's terms, the time-blocked held-out log predictive density
(:func:`fogbayes.loop.holdout.score`) under the noise model with and without the walk, and
with least-squares coefficients under the walk: can held-out prediction choose?
``--coverage`` prints, for the base model's terms by GLS with and without the walk, the
error against the truth beside the calibration's own stated standard error (RMS over the
record of the model's prediction s.e. from ``cov_beta``): is the stated uncertainty honest? The error is
study_random's: RMS of 10 s means of (model - truth), mean kept; the plain ``fogbayes fit
-m bias-t`` is the floor. Rows go to stdout as JSON lines.
"""

from __future__ import annotations

import argparse
import json
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

import study_random as sr  # noqa: E402


def _least_squares(ctx, terms) -> np.ndarray:
    """Deterministic model at every sample, coefficients by count-weighted least squares."""
    from fogbayes.effects.terms import design

    X = ctx.block_design(list(terms))
    w = np.sqrt(ctx.grid.count * ctx.grid.mask)
    beta = np.linalg.lstsq(X * w[:, None], ctx.y * w, rcond=None)[0]
    return design(list(terms), ctx.cov) @ beta


def row(seed: int, orders: str | None = None) -> dict:
    import fogbayes  # noqa: F401
    from fogbayes.loop.context import make_context
    from fogbayes.loop.fitting import fit_terms
    from fogbayes.loop import run_loop
    from fogbayes.loop.constant import ieee_constant
    from fogbayes.thermal import workflow as thermal

    case = sr.draw(seed)
    rec, true_det, _ = sr.build(case)
    res = run_loop(rec, "bias-t", orders=orders, seed=case["seed"] % 2**31)
    ctx, flag = res.context, res.context.outlier

    def err(det):
        return sr._err(rec.time, det, true_det, flag)

    plain = thermal.fit_recording(rec, model="bias-t")
    no_walk = make_context(rec, random_walk=False)
    out = dict(seed=seed, family=case["family"], added=res.effects,
               plain=err(ctx.rate - np.asarray(thermal.compensate_recording(rec, plain)["output"])),
               loop=err(ctx.rate - np.asarray(res.compensated["output"], float)),
               gls_walk=err(ctx.rate - ieee_constant(ctx, fit_terms(
                   ctx, res.fit.terms, spec=res.fit.noise.spec)).residual),
               gls_no_walk=err(ctx.rate - ieee_constant(no_walk, fit_terms(no_walk, res.fit.terms)).residual),
               least_squares=err(_least_squares(ctx, res.fit.terms)))
    return out


def lpd_row(seed: int) -> dict:
    import fogbayes  # noqa: F401
    from fogbayes.loop.context import make_context
    from fogbayes.loop.fitting import fit_terms
    from fogbayes.loop import holdout
    from fogbayes.loop.bases import base_terms

    rec = sr.build(sr.draw(seed))[0]
    walk, no_walk = make_context(rec), make_context(rec, random_walk=False)
    fw = fit_terms(walk, base_terms(walk, "bias-t"))
    fn = fit_terms(no_walk, base_terms(no_walk, "bias-t"))
    return dict(seed=seed, lpd_gls_walk=holdout.score(walk, fw).lpd,
                lpd_gls_no_walk=holdout.score(no_walk, fn).lpd,
                lpd_least_squares_walk=holdout.score(walk, fw, ols=True).lpd)


def coverage_row(seed: int) -> dict:
    import fogbayes  # noqa: F401
    from fogbayes.loop.context import make_context
    from fogbayes.loop.fitting import fit_terms
    from fogbayes.effects.terms import design
    from fogbayes.loop.bases import base_terms
    from fogbayes.loop.constant import ieee_constant

    case = sr.draw(seed)
    rec, true_det, _ = sr.build(case)
    out = dict(seed=seed, family=case["family"])
    for name, walk in (("walk", True), ("no_walk", False)):
        ctx = make_context(rec, random_walk=walk)
        terms = base_terms(ctx, "bias-t")
        fit = ieee_constant(ctx, fit_terms(ctx, terms))
        X = design(list(terms), ctx.cov)
        se = np.sqrt(np.einsum("ij,jk,ik->i", X, np.asarray(fit.noise.cov_beta), X))
        out[f"err_{name}"] = sr._err(rec.time, ctx.rate - fit.residual, true_det, ctx.outlier)
        out[f"se_{name}"] = float(np.sqrt(np.mean(se ** 2)))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", nargs=2, type=int, default=(2, 13), metavar=("FIRST", "STOP"))
    ap.add_argument("--orders", default=None, help="the loop's base order (default: the loop's)")
    ap.add_argument("--lpd", action="store_true", help="held-out predictive densities instead")
    ap.add_argument("--coverage", action="store_true", help="error against stated s.e. instead")
    a = ap.parse_args()
    one = lpd_row if a.lpd else coverage_row if a.coverage else (
        lambda s: row(s, a.orders))
    for s in range(*a.seeds):
        print(json.dumps(one(s)), flush=True)


if __name__ == "__main__":
    main()
