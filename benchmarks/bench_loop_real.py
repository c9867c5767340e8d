"""The closed loop on measured sensor noise: planted effects in the ADIS16405 static runs.

Usage::

    python benchmarks/bench_loop_real.py [--workers 1] [--out benchmarks/loop_real.json]
                                         [--runs 1,...,6] [--axes 0,1,2] [--only step,clean]
                                         [--scale 0.003]
    python benchmarks/bench_loop_real.py --summary [--out ...]
    python benchmarks/bench_loop_real.py --timing shupe_lag300

Each record is the deterministic part of a simulated chamber test plus *measured* noise:

* noise: gyro axis ``a`` of ADIS16405 static run ``r`` (``../shared/data/measured``,
  100 Hz, 2.78 h), averaged to 10 Hz, its mean removed, times ``SCALE`` (0.003: ARW
  ~0.007 deg/sqrt(h), bias instability ~0.1 deg/h, rate random walk ~0.3 deg/h^1.5, a
  tactical FOG; the raw ADIS terms are N 2.46, B 31.6, K ~105) in deg/h. The noise is
  what the sensor recorded: flicker, walk, Markov-like wander and quantization as they are,
  not the loop's own noise model;
* deterministic part (``fogbayes.simulate``, noise-free): the generic chamber programme
  sized to 10 000 s (-20..60 deg C), the declared quadratic bias in T, and at most one
  planted effect in one of several *shapes* (:data:`SHAPES`): the Shupe term through two
  sensor lags, a rate-type hysteresis (tanh) at two rate scales, a memory (play-operator)
  hysteresis the loop has no term for, steps at 30 % and 75 % of the record, warm-ups of
  tau 600 s and 2400 s, a first-order lag, a gradient, a cubic in T.

Per record: what the loop added (deterministic effects and noise components apart), and
the *error against the truth*: the RMS of 10 s block means of (fitted deterministic model
- true deterministic part), mean removed (a constant offset cannot be told from the noise's
own mean), for the loop's final model, the plain ``fogbayes fit -m bias-t`` and the
true-form fit (base model + the planted effect's true shape with a free amplitude, fitted
by the loop's GLS on the loop's blocks). The oracle's likelihood ratio says whether the
effect is detectable at all (family-wise p < 0.01 over the loop's candidates).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)
sys.path.insert(0, REPO)

SHARED = os.environ.get("FOGBAYES_SHARED", os.path.join(REPO, "..", "shared"))
ADIS = os.path.join(SHARED, "data", "measured", "adis16405_static_ucalgary")
SCALE = 0.003
DURATION = 10000.0
FS = 10.0
QUADRATIC = {"coeffs": [0.5, 0.01, 2e-4], "T_ref": 20.0}
DEFAULT_OUT = os.path.join(HERE, "loop_real.json")

#: shape name -> (loop effect that is right, simulator effects, scenario options)
SHAPES = {
    "clean": (None, {}, {}),
    "shupe_lag300": ("temperature_rate", {"temperature_rate": {"coeff": 1.2}}, {}),
    "shupe_lag60": ("temperature_rate", {"temperature_rate": {"coeff": 1.2}},
                    {"lags": (60.0, 900.0)}),
    "hyst_rate_r05": ("thermal_hysteresis",
                      {"thermal_hysteresis": {"size": 0.8, "rate_scale": 0.05}}, {}),
    "hyst_rate_r02": ("thermal_hysteresis",
                      {"thermal_hysteresis": {"size": 0.8, "rate_scale": 0.02}}, {}),
    "hyst_play_w4": ("thermal_hysteresis",
                     {"thermal_hysteresis": {"size": 0.8, "width": 4.0}}, {}),
    "hyst_play_w10": ("thermal_hysteresis",
                      {"thermal_hysteresis": {"size": 0.8, "width": 10.0}}, {}),
    "step_30": ("step", {"step": {"size": 0.8, "time": 0.3 * DURATION}}, {}),
    "step_75": ("step", {"step": {"size": 0.8, "time": 0.75 * DURATION}}, {}),
    "warmup_600": ("time_drift", {"time_drift": {"amplitude": 3.0, "tau": 600.0}}, {}),
    "warmup_2400": ("time_drift", {"time_drift": {"amplitude": 3.0, "tau": 2400.0}}, {}),
    "lag_1800": ("thermal_lag", {"thermal_lag": {"coeff": 0.04, "tau": 1800.0}}, {}),
    "gradient": ("temperature_gradient", {"temperature_gradient": {"coeff": 0.12}}, {}),
    "cubic": ("temperature_order", {"temperature_order": {
        "coeffs": QUADRATIC["coeffs"] + [2e-5], "T_ref": 20.0}}, {}),
}
def adis_noise(run: int, axis: int, *, scale: float = SCALE, reverse: bool = False) -> np.ndarray:
    """10 Hz block means of ADIS16405 run ``run`` gyro ``axis`` (deg/h), mean removed, x
    ``scale``; ``reverse``: the same noise played backwards (another realisation of a
    stationary process, with the same spectrum)."""
    d = np.load(os.path.join(ADIS, f"adis_16405_imu{run}.npz"))["data"][:, axis]
    x = d[: d.size // 10 * 10].reshape(-1, 10).mean(axis=1)
    x = x[::-1] if reverse else x
    return scale * 3600.0 * (x - x.mean())


def build(case: dict):
    """(recording, true deterministic part deg/h, true effect column deg/h or None)."""
    from fogbayes.data import Recording
    from fogbayes.simulate.scenarios import simulate

    right, effects, opts = SHAPES[case["shape"]]
    law = {"temperature_order": dict(QUADRATIC), **effects}
    sim = simulate("thermal", seed=case["seed"], fs=FS, duration=DURATION, effects=law,
                   noise={}, temperature_noise=0.01, **opts)
    rec = sim.recording
    det = np.asarray(sim.truth.deterministic, float).copy()
    base_part = np.asarray(sim.truth.effects["temperature_order"], float)
    if case["shape"] == "cubic":  # the planted part is the cubic on top of the quadratic
        T = np.asarray(sim.truth.covariates.temperatures)[:, 0]
        effect_col = 2e-5 * (T - 20.0) ** 3
    else:
        effect_col = det - base_part if effects else None
    noise = adis_noise(case["run"], case["axis"], scale=case.get("scale", SCALE),
                       reverse=case.get("reverse", False))[: rec.n]
    out = Recording(time=rec.time, output=det + noise, unit="deg/h",
                    temperatures=rec.temperatures, temperature_names=rec.temperature_names,
                    meta=rec.meta)
    return out, det, effect_col


def _err(t, model_det, true_det, flag) -> float:
    from fogbayes.loop.metrics import block_rms

    d = model_det - true_det
    return block_rms(t, d - np.mean(d[~flag]), flag)


def oracle(ctx, base, effect_col, spec=None):
    """True-form GLS fit: base terms + the planted effect's true shape (free amplitude),
    under the noise structure ``spec`` (default: the loop's base one)."""
    from fogbayes.effects.terms import design
    from fogbayes.inference import noise_fit as nfit

    X = ctx.block_design(list(base))
    F = design(list(base), ctx.cov)
    if effect_col is not None:
        X = np.column_stack([X, ctx.grid.mean(effect_col)])
        F = np.column_stack([F, effect_col])
    nf = nfit.fit_noise(spec or ctx.spec, ctx.y, X, ctx.grid.mask, ctx.grid.w)
    return F @ nf.beta, nf.loglik


def run_case(case: dict) -> dict:
    import fogbayes  # noqa: F401
    from fogbayes.loop import evidence as ev
    from fogbayes.loop import run_loop
    from fogbayes.loop.bases import base_terms
    from fogbayes.loop.noise_model import components
    from fogbayes.thermal import workflow as thermal

    rec, true_det, effect_col = build(case)
    t0 = time.time()
    res = run_loop(rec, "bias-t", seed=case["seed"])
    wall = time.time() - t0
    ctx = res.context
    flag = ctx.outlier
    rate = ctx.rate
    loop_det = rate - np.asarray(res.compensated["output"], float)
    plain_doc = thermal.fit_recording(rec, model="bias-t")
    plain_det = rate - np.asarray(thermal.compensate_recording(rec, plain_doc)["output"], float)
    base = base_terms(ctx, "bias-t")
    base_det, ll0 = oracle(ctx, base, None)
    orc_det, ll1 = oracle(ctx, base, effect_col)
    right = SHAPES[case["shape"]][0]
    det_added = [s.effect for s in res.steps if s.term is not None]
    lr = max(2.0 * (ll1 - ll0), 0.0)
    row = dict(case, right=right, added=res.effects, deterministic=det_added,
               noise_model=[c["tau_c_s"] for c in components(res.fit)],
               wall_s=wall, err_loop=_err(rec.time, loop_det, true_det, flag),
               err_plain=_err(rec.time, plain_det, true_det, flag),
               err_oracle=_err(rec.time, orc_det, true_det, flag),
               err_base=_err(rec.time, base_det, true_det, flag),
               rms_before=res.initial.rms, rms_after=res.final.rms, stop=res.stop.reason,
               not_kept=[x["effect"] for x in (res.holdout or {}).get("not_kept", [])],
               oracle_lr=lr,
               oracle_log10_p_fw=float(ev.fw_log_p(min(ev.log_chi2_sf(lr, 1), 0.0), 9)
                                       / np.log(10)) if right else None)
    row["first_right"] = bool(right) and det_added[:1] == [right]
    return row


def cases(runs, axes, only=None, scale: float = SCALE) -> list[dict]:
    """Every shape on axis ``axes[0]`` of each run; clean records on every axis, forwards
    and backwards (the null needs more noise realisations than one per run)."""
    out = []
    for r in runs:
        for a in axes:
            for k, shape in enumerate(SHAPES):
                if (only and shape not in only) or (shape != "clean" and a != axes[0]):
                    continue
                for rev in ((False, True) if shape == "clean" else (False,)):
                    out.append(dict(shape=shape, run=r, axis=a, seed=100 * r + 10 * a + k,
                                    reverse=rev, scale=scale))
    return out


def summarise(rows: list[dict]) -> str:
    """Totals, one row per shape, then every record."""
    eff = [r for r in rows if r["right"]]
    det = [r for r in eff if r["oracle_log10_p_fw"] < -2]
    clean = [r for r in rows if not r["right"]]
    ok13 = sum(r["err_loop"] <= 1.3 * r["err_oracle"] for r in rows)
    ok11 = sum(r["err_loop"] <= 1.1 * r["err_plain"] for r in rows)
    walls = [r["wall_s"] for r in rows]
    lines = [f"records: {len(rows)} ({len(eff)} with an effect, {len(clean)} clean)",
             f"right deterministic effect first, among those the oracle detects "
             f"(family-wise p < 0.01): {sum(r['first_right'] for r in det)}/{len(det)}; "
             f"among all with an effect: {sum(r['first_right'] for r in eff)}/{len(eff)}",
             f"clean records with no deterministic effect added: "
             f"{sum(not r['deterministic'] for r in clean)}/{len(clean)}",
             f"error <= 1.3x the true-form fit's: {ok13}/{len(rows)} "
             f"(clean: the true form is the base model)",
             f"error <= 1.1x the plain fit's: {ok11}/{len(rows)}",
             f"loop wall time per record: median {np.median(walls):.0f} s, max {max(walls):.0f} s",
             "", "| shape | records | oracle detects | right first (detected) | nothing added "
             "| loop/true-form median, max | loop/plain max |", "|---|---|---|---|---|---|---|"]
    for shape in SHAPES:
        g = [r for r in rows if r["shape"] == shape]
        if not g:
            continue
        d = [r for r in g if r["right"] and r["oracle_log10_p_fw"] < -2]
        ro = np.array([r["err_loop"] / r["err_oracle"] for r in g])
        rp = np.array([r["err_loop"] / r["err_plain"] for r in g])
        lines.append(f"| {shape} | {len(g)} | {len(d) if g[0]['right'] else '-'} | "
                     f"{sum(r['first_right'] for r in d) if g[0]['right'] else '-'} | "
                     f"{sum(not r['deterministic'] for r in g)} | "
                     f"{np.median(ro):.2f}, {ro.max():.2f} | {rp.max():.2f} |")
    lines += ["", "| shape | run | axis | added | noise GM tau_c (s) | loop | plain | true form | "
              "loop/true | loop/plain | oracle log10 p_fw | wall s |",
              "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lp = r["oracle_log10_p_fw"]
        gm = ", ".join(f"{t:.0f}" for t in r.get("noise_model") or []) or "-"
        lines.append(f"| {r['shape']}{' (rev)' if r.get('reverse') else ''} | {r['run']} | "
                     f"{r['axis']} | {', '.join(r['added']) or '-'} | {gm} | {r['err_loop']:.4f} | "
                     f"{r['err_plain']:.4f} | {r['err_oracle']:.4f} | "
                     f"{r['err_loop'] / r['err_oracle']:.2f} | {r['err_loop'] / r['err_plain']:.2f} "
                     f"| {'-' if lp is None else f'{lp:.1f}'} | {r['wall_s']:.0f} |")
    return "\n".join(lines)


def long_noise(n: int, axis: int = 0) -> np.ndarray:
    """Runs 1, 2, 3, ... of one axis end to end (10 Hz, deg/h, x SCALE), each shifted so its
    first 100 s continue the previous run's last 100 s (no artificial step at the joins)."""
    parts, run = [], 1
    while sum(p.size for p in parts) < n:
        x = adis_noise(run, axis)
        if parts:
            x = x - x[:1000].mean() + parts[-1][-1000:].mean()
        parts.append(x)
        run += 1
    return np.concatenate(parts)[:n]


def timing(shape: str = "shupe_lag300") -> None:
    """`fogbayes loop` in a fresh process on a 6.3 h, 10 Hz measured-noise record."""
    import subprocess
    import tempfile

    from fogbayes.simulate.scenarios import simulate

    right, effects, opts = SHAPES[shape]
    law = {"temperature_order": dict(QUADRATIC), **effects}
    dur = 6.3 * 3600.0
    if "step" in effects:
        law["step"] = dict(effects["step"], time=0.3 * dur)
    sim = simulate("thermal", seed=7, fs=FS, duration=dur, effects=law, noise={},
                   temperature_noise=0.01, **opts)
    rec = sim.recording
    y = np.asarray(sim.truth.deterministic, float) + long_noise(rec.n)
    with tempfile.TemporaryDirectory() as d:
        path = os.path.join(d, "chamber.csv")
        T = np.asarray(rec.temperatures)
        np.savetxt(path, np.column_stack([rec.time, y, T]), delimiter=",", fmt="%.9g",
                   header="time,output," + ",".join(
                       ["temperature"] + [f"temperature_{k + 2}" for k in range(T.shape[1] - 1)]),
                   comments="")
        t0 = time.time()
        out = subprocess.run([sys.executable, "-m", "fogbayes", "loop", path, "-m", "bias-t",
                              "--output-unit", "deg/h", "--json", os.path.join(d, "loop.json"),
                              "--compensated", os.path.join(d, "comp.csv")],
                             capture_output=True, text=True)
        wall = time.time() - t0
    print(out.stdout + out.stderr)
    print(f"{shape}: 6.3 h at 10 Hz ({rec.n} rows), measured noise: `fogbayes loop` "
          f"{wall:.1f} s (fresh process, compile included)")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--workers", type=int, default=1)
    ap.add_argument("--out", default=DEFAULT_OUT)
    ap.add_argument("--runs", default="1,2,3,4,5,6")
    ap.add_argument("--axes", default="0,1,2")
    ap.add_argument("--only", default=None)
    ap.add_argument("--scale", type=float, default=SCALE, help="noise scale (module doc)")
    ap.add_argument("--summary", action="store_true", help="only summarise the rows in --out")
    ap.add_argument("--timing", default=None, metavar="SHAPE",
                    help="time `fogbayes loop` on a 6.3 h, 10 Hz record with SHAPE planted")
    a = ap.parse_args()
    if a.timing:
        timing(a.timing)
        return
    if a.summary:
        print(summarise(json.load(open(a.out))))
        return
    todo = cases([int(x) for x in a.runs.split(",")], [int(x) for x in a.axes.split(",")],
                 a.only.split(",") if a.only else None, a.scale)
    done = json.load(open(a.out)) if os.path.exists(a.out) else []
    key = lambda c: (c["shape"], c["run"], c["axis"], c["seed"], c.get("reverse", False),
                     c.get("scale", SCALE))
    seen = {key(r) for r in done}
    todo = [c for c in todo if key(c) not in seen]
    print(f"{len(todo)} records to run ({len(done)} done)", flush=True)
    with ProcessPoolExecutor(a.workers) as pool:
        for r in pool.map(run_case, todo):
            done.append(r)
            json.dump(done, open(a.out, "w"), indent=1, default=float)
            print(r["shape"], r["run"], r["axis"], r.get("reverse"), "->", r["added"],
                  f"loop/oracle {r['err_loop'] / r['err_oracle']:.2f}",
                  f"loop/plain {r['err_loop'] / r['err_plain']:.2f}", f"{r['wall_s']:.0f}s",
                  flush=True)
    print(summarise(done))


if __name__ == "__main__":
    main()
