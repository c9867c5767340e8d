"""Closed-loop study and timing: does the loop add the right effect first, and nothing on clean data?

Usage::

    python benchmarks/bench_loop.py study [--quick] [--noise walk] [--workers 2] [--out F.json]
    python benchmarks/bench_loop.py timing           # 6 h, 10 Hz record through `fogbayes loop`
    python benchmarks/bench_loop.py measured         # ADIS16405 (allan) and PAN TVAC (bias-t)
    python benchmarks/bench_loop.py detectability    # right first among what the oracle detects
    python benchmarks/bench_loop.py sweep            # 0.5x-16x sizes, 50 Hz 1 h and 1 Hz 12 h

Study design (every case a fresh simulated recording, fixed seeds):
  * every effect name, present but undeclared, on its base model (thermal effects on
    ``bias-t`` over the generic heating/cooling test; scale-factor effects on ``composite``
    over paper 000's rate table; ``markov_noise`` on ``bias-t`` and ``allan``);
  * magnitudes 1x and 2x the simulator's registry default, noise mixes fog / flicker / walk
    / white (:data:`fogbayes.loop.testbed.NOISE_MIXES`), sample rates 1, 2, 10 Hz, durations
    3 h and 6 h, the generic thermal test and paper 004's programme, several seeds;
  * clean recordings (no extra effect) over the same grid.
Per case: the first added effect; the final 10 s-block RMS against the oracle's (the true
model -- base terms plus the planted effect at its true parameters -- fitted the same way);
the run time. ``RESULTS_loop.md`` holds the table.
"""

from __future__ import annotations

import argparse
import itertools
import json
import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor

import numpy as np

# Run against the checkout this script lives in, whatever `pip install -e` points at.
REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, REPO)
os.environ["PYTHONPATH"] = REPO + os.pathsep + os.environ.get("PYTHONPATH", "")

THERMAL = ("temperature_order", "temperature_rate", "temperature_gradient", "thermal_hysteresis",
           "thermal_lag", "time_drift", "periodic", "step", "markov_noise")
#: The study's thermal configurations: magnitude, noise mix, fs (Hz), duration (s), profile.
CONFIGS = [(1.0, "default", 10.0, 3 * 3600, "thermal"),
           (2.0, "flicker", 1.0, 6 * 3600, "thermal"),
           (1.0, "walk", 10.0, 6 * 3600, "paper004"),
           (2.0, "white", 2.0, 3 * 3600, "thermal")]
DEFAULT_OUT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "loop_study.json")
RATE_TABLE = ("scale_factor_nonlinearity", "scale_factor_asymmetry", "scale_factor_temperature")


def _record(case: dict):
    """The simulated test record of one study/sweep case (fogbayes.loop.testbed)."""
    from fogbayes.loop.testbed import make_record

    return make_record(case["effect"], seed=case["seed"], duration=case["duration"],
                       fs=case["fs"], magnitude=case["magnitude"], noise=case["noise"],
                       profile=case["profile"], segments=case.get("segments"))


def loop_row(case: dict, res, wall: float) -> dict:
    """The study row of one loop run: what it added first, its evidence, RMS before/after."""
    from fogbayes.loop.noise_model import components

    first = res.steps[0].evidence if res.steps else {}
    return dict(case, added=res.effects, noise_components=len(components(res.fit)),
                rms_initial=res.initial.rms, rms_final=res.final.rms,
                wall_s=wall, stop=res.stop.reason,
                alternatives=[a["effect"] for a in first.get("alternatives", [])],
                duels=[{k: d[k] for k in ("leader", "other", "d_2loglik_other_minus_leader",
                                          "p_leader", "p_other", "verdict")}
                       for d in first.get("duels", [])],
                first_log10_p_fw=first["log10_p_familywise"] if res.steps else
                (res.stop.evidence or {}).get("log10_p_familywise"))


def oracle_rms(res, model: str, effect: str, params: dict) -> float:
    """10 s-block RMS of the true model (base + the planted effect at its true parameters),
    fitted on the loop's own context as the loop fits its models."""
    from fogbayes.loop.fitting import fit_terms
    from fogbayes.loop.bases import base_terms
    from fogbayes.loop.metrics import block_rms
    from fogbayes.loop.testbed import oracle_terms

    ctx = res.context
    ofit = fit_terms(ctx, oracle_terms(ctx, base_terms(ctx, model), effect, params))
    return block_rms(ctx.cov.t, ofit.residual, ctx.outlier)


def run_case(case: dict) -> dict:
    import fogbayes  # noqa: F401
    from fogbayes.loop import run_loop

    tr = _record(case)
    t0 = time.time()
    res = run_loop(tr.recording, case["model"], max_steps=case.get("max_steps", 3), seed=case["seed"])
    out = loop_row(case, res, time.time() - t0)
    if case["effect"] is not None:
        out["rms_oracle"] = oracle_rms(res, case["model"], case["effect"], tr.effect_params)
    return out


#: Clean records per configuration: 15 seeds x 4 thermal + 6 x 2 rate-table = 72, so that
#: 72/72 would put the 95 % Clopper-Pearson lower bound of "nothing added" at 0.950.
CLEAN_SEEDS = {"bias-t": 15, "composite": 6}


def cases(quick: bool, effects: tuple[str, ...] | None = None, first_seed: int = 0,
          noise_mix: str | None = None) -> list[dict]:
    """The study's records; ``quick``: seeds 0-1 (2 clean) of configurations A, B and the rate
    table, or of the one configuration whose noise mix is ``noise_mix``."""
    seeds = tuple(first_seed + k for k in ((0, 1) if quick else (0, 1, 2)))
    grid = []

    def want(eff):
        return effects is None or str(eff) in effects

    for eff in THERMAL + (None,):
        if not want(eff):
            continue
        for mag, noise, fs, dur, prof in CONFIGS:
            if noise_mix is not None and noise != noise_mix:
                continue
            if quick and noise_mix is None and noise in ("walk", "white"):
                continue
            for sd in (range(first_seed, first_seed + CLEAN_SEEDS["bias-t"]) if eff is None
                       and not quick else seeds):
                grid.append(dict(effect=eff, model="bias-t", profile=prof, magnitude=mag,
                                 noise=noise, fs=fs, duration=float(dur), seed=sd))
    for eff in RATE_TABLE + (None,):
        if not want(eff) or noise_mix is not None:
            continue
        for mag, noise, fs in [(1.0, "default", 10.0), (0.1, "flicker", 2.0)]:
            for sd in (range(first_seed, first_seed + CLEAN_SEEDS["composite"]) if eff is None
                       and not quick else seeds):
                grid.append(dict(effect=eff, model="composite", profile="ratetable",
                                 magnitude=mag, noise=noise, fs=fs, duration=2 * 3600.0, seed=sd))
    return grid


def clopper_pearson(k: int, n: int, level: float = 0.95) -> tuple[float, float]:
    """Exact binomial interval of k successes in n trials."""
    from scipy import stats

    a = 1.0 - level
    lo = 0.0 if k == 0 else float(stats.beta.ppf(a / 2, k, n - k + 1))
    hi = 1.0 if k == n else float(stats.beta.ppf(1 - a / 2, k + 1, n - k))
    return lo, hi


def _right_first(r: dict) -> bool:
    """The planted effect came first. ``markov_noise`` is a noise component: since the noise
    model is chosen apart from the effects (rows with ``noise_components``), right means a
    Gauss-Markov component in the noise model and no deterministic effect invented."""
    if r["effect"] == "markov_noise" and "noise_components" in r:
        return not r["added"] and r["noise_components"] > 0
    return r["added"][:1] == [r["effect"]]


def summarise(rows: list[dict]) -> str:
    lines = ["| effect | base | cases | right first | right first or listed alternative "
             "| nothing added | final/oracle RMS (median, max) | within 10 % |",
             "|---|---|---|---|---|---|---|---|"]
    key = lambda r: (str(r["effect"]), r["model"])
    tot = {"right": 0, "n": 0, "clean": 0, "nc": 0, "rms": 0, "alt": 0}
    for (eff, model), grp in itertools.groupby(sorted(rows, key=key), key=key):
        g = list(grp)
        if eff == "None":
            clean = sum(1 for r in g if not r["added"])
            tot["clean"] += clean
            tot["nc"] += len(g)
            lines.append(f"| (clean) | {model} | {len(g)} | - | - | {clean}/{len(g)} | - | - |")
            continue
        right = sum(1 for r in g if _right_first(r))
        alt = sum(1 for r in g if _right_first(r) or eff in r.get("alternatives", []))
        ratio = np.array([r["rms_final"] / r["rms_oracle"] for r in g])
        ok = int(np.sum(ratio <= 1.1))
        tot["right"] += right
        tot["alt"] += alt
        tot["n"] += len(g)
        tot["rms"] += ok
        lines.append(f"| {eff} | {model} | {len(g)} | {right}/{len(g)} | {alt}/{len(g)} | - | "
                     f"{np.median(ratio):.3f}, {ratio.max():.3f} | {ok}/{len(g)} |")
    if tot["n"]:
        lo, hi = clopper_pearson(tot["right"], tot["n"])
        lines.append(f"\nright effect first {tot['right']}/{tot['n']} = "
                     f"{100 * tot['right'] / tot['n']:.1f} % (95 % CI {100 * lo:.1f}-{100 * hi:.1f}); "
                     f"right first or listed as an indistinguishable alternative {tot['alt']}/{tot['n']}; "
                     f"final RMS within 10 % of the oracle {tot['rms']}/{tot['n']}")
    if tot["nc"]:
        lo, hi = clopper_pearson(tot["clean"], tot["nc"])
        lines.append(f"nothing added on clean records {tot['clean']}/{tot['nc']} = "
                     f"{100 * tot['clean'] / tot['nc']:.1f} % (95 % Clopper-Pearson "
                     f"{100 * lo:.1f}-{100 * hi:.1f} %)")
    return "\n".join(lines)


def run_cases(todo: list[dict], out: str, workers: int, fn=run_case) -> list[dict]:
    """Run ``fn`` on the cases not yet in ``out`` (a JSON list of rows, rewritten after each)."""
    done = json.load(open(out)) if os.path.exists(out) else []
    seen = {json.dumps({k: r[k] for k in todo[0]}, sort_keys=True) for r in done}
    todo = [c for c in todo if json.dumps(c, sort_keys=True) not in seen]
    print(f"{len(todo)} cases to run ({len(done)} already done)", flush=True)
    with ProcessPoolExecutor(workers) as pool:
        for r in pool.map(fn, todo):
            done.append(r)
            json.dump(done, open(out, "w"), indent=1, default=float)
            print(*(r[k] for k in todo[0]), "->", r["added"], f"{r['wall_s']:.1f}s", flush=True)
    return done


def study(args) -> None:
    todo = cases(args.quick, tuple(args.effects.split(",")) if args.effects else None,
                 args.first_seed, args.noise)
    print(summarise(run_cases(todo, args.out, args.workers)))


#: The magnitude sweep: every effect at sizes outside the study's 1x/2x (config A, the rate
#: table's default), and two sampling set-ups the study does not have (1 h at 50 Hz, 12 h at
#: 1 Hz, both with the "fog" noise mix), on fresh seeds from 200.
SWEEP_MAGNITUDES = (0.5, 4.0, 16.0)
SWEEP_SETUPS = [(2.0, "fog", 50.0, 3600.0, "thermal"), (2.0, "fog", 1.0, 12 * 3600.0, "thermal")]


def sweep_cases(first_seed: int = 200, n_seeds: int = 3) -> list[dict]:
    seeds = range(first_seed, first_seed + n_seeds)
    grid = []
    for eff in THERMAL:
        for mag in SWEEP_MAGNITUDES:
            grid += [dict(effect=eff, model="bias-t", profile="thermal", magnitude=mag,
                          noise="default", fs=10.0, duration=3 * 3600.0, seed=sd) for sd in seeds]
        for mag, noise, fs, dur, prof in SWEEP_SETUPS:
            grid += [dict(effect=eff, model="bias-t", profile=prof, magnitude=mag, noise=noise,
                          fs=fs, duration=float(dur), seed=sd) for sd in seeds[:2]]
    for eff in RATE_TABLE:
        for mag in SWEEP_MAGNITUDES:
            grid += [dict(effect=eff, model="composite", profile="ratetable", magnitude=mag,
                          noise="default", fs=10.0, duration=2 * 3600.0, seed=sd) for sd in seeds]
    for mag, noise, fs, dur, prof in SWEEP_SETUPS:  # clean records of the two new set-ups
        grid += [dict(effect=None, model="bias-t", profile=prof, magnitude=mag, noise=noise,
                      fs=fs, duration=float(dur), seed=sd) for sd in range(first_seed, first_seed + 6)]
    return grid


def sweep(args) -> None:
    """Right effect first by size and sampling set-up (see :data:`SWEEP_MAGNITUDES`)."""
    out = args.out if args.out != DEFAULT_OUT else os.path.join(os.path.dirname(__file__),
                                                                 "loop_sweep.json")
    done = run_cases(sweep_cases(args.first_seed if args.first_seed else 200), out, args.workers)
    key = lambda r: (r["noise"], r["fs"], r["duration"], r["magnitude"])
    for k, grp in itertools.groupby(sorted(done, key=key), key=key):
        print(f"\n## noise {k[0]}, {k[1]:g} Hz, {k[2] / 3600:g} h, magnitude x{k[3]:g}")
        print(summarise(list(grp)))


def oracle_case(case: dict) -> dict:
    """The oracle's own evidence on one study record: 2 (logL(true model) - logL(base)).

    The true model at its true parameters (nothing searched; for ``markov_noise`` the
    Gauss-Markov time constant known, its variance and the other noise hyperparameters by
    ML), both fitted as the loop fits its models.
    """
    import fogbayes  # noqa: F401
    from fogbayes.loop.context import make_context
    from fogbayes.loop.fitting import fit_terms
    from fogbayes.loop.bases import base_terms
    from fogbayes.loop.testbed import oracle_terms

    tr = _record(case)
    ctx = make_context(tr.recording)
    base = base_terms(ctx, case["model"])
    fit0 = fit_terms(ctx, base)
    if case["effect"] == "markov_noise":
        lr, dof = 2.0 * (_fixed_tau_fit(ctx, fit0, tr.effect_params.get("tau_c", 300.0))
                         - fit0.loglik), 1
    else:
        terms = oracle_terms(ctx, base, case["effect"], tr.effect_params)
        fit1 = fit_terms(ctx, terms)
        lr, dof = 2.0 * (fit1.loglik - fit0.loglik), fit1.X.shape[1] - fit0.X.shape[1]
    return dict(case, oracle_lr=max(lr, 0.0), oracle_dof=dof)


#: candidates a thermal bias-t step weighs (the family of its Sidak correction)
N_CAND = 9


def oracle_log10_p_fw(o: dict) -> float:
    """Family-wise p of the oracle's ratio: chi^2 with the effect's columns; for markov_noise
    (one variance at its boundary, tau_c known) the 50:50 chi^2_0 : chi^2_1 mixture (Self &
    Liang 1987); Sidak over :data:`N_CAND`."""
    from fogbayes.loop import evidence as ev

    lp = ev.log_chi2_sf(o["oracle_lr"], o["oracle_dof"])
    if o["effect"] == "markov_noise":
        lp += np.log(0.5) if o["oracle_lr"] > 0 else 0.0
    return ev.fw_log_p(min(lp, 0.0), N_CAND) / np.log(10)


def detectability(args) -> None:
    """Right effect first among the study records whose effect the oracle itself detects.

    The oracle knows the true parameters, so it pays nothing for a search: its family-wise
    p < 0.01 bounds what the loop, at the same level, can detect. Oracle ratios are cached
    in ``loop_oracle.json`` (delete it to recompute, ~25 min on 1 core).
    """
    here = os.path.dirname(__file__)
    rows = []
    for f in ("loop_study.json", "loop_study_fresh.json"):
        rows += [r for r in json.load(open(os.path.join(here, f))) if r["effect"] is not None]
    keys = ("effect", "model", "profile", "magnitude", "noise", "fs", "duration", "seed")
    out = os.path.join(here, "loop_oracle.json")
    orc = json.load(open(out)) if os.path.exists(out) else []
    if [{k: o[k] for k in keys} for o in orc] != [{k: r[k] for k in keys} for r in rows]:
        with ProcessPoolExecutor(args.workers) as pool:
            orc = list(pool.map(oracle_case, [{k: r[k] for k in keys} for r in rows]))
        json.dump(orc, open(out, "w"), indent=1, default=float)
    detect = [oracle_log10_p_fw(o) < np.log10(0.01) for o in orc]
    print(f"oracle detects {sum(detect)}/{len(rows)} planted effects at family-wise 0.01")
    print("| effect | cases | oracle detects | right first among them | misses where the oracle "
          "does not detect |\n|---|---|---|---|---|")
    key = lambda x: x[0]["effect"]
    for eff, grp in itertools.groupby(sorted(zip(rows, detect), key=key), key=key):
        g = list(grp)
        d = [r for r, ok in g if ok]
        right = sum(r["added"][:1] == [eff] for r in d)
        undet = sum(r["added"][:1] != [eff] for r, ok in g if not ok)
        print(f"| {eff} | {len(g)} | {len(d)} | {right}/{len(d)} | {undet} |")
    right = sum(r["added"][:1] == [r["effect"]] for r, ok in zip(rows, detect) if ok)
    n = sum(detect)
    lo, hi = clopper_pearson(right, n)
    print(f"right first among detectable: {right}/{n} = {100 * right / n:.1f} % "
          f"(95 % CI {100 * lo:.1f}-{100 * hi:.1f})")


def timing(args) -> None:
    """Wall time of `fogbayes loop` (a fresh process: compile included) on a 6 h 10 Hz record."""
    import subprocess
    import tempfile

    import fogbayes  # noqa: F401
    from fogbayes.data import save
    from fogbayes.loop.testbed import make_record

    tmp = tempfile.mkdtemp()
    rec = make_record("thermal_lag", seed=5, duration=6 * 3600.0, fs=10.0).recording
    path = os.path.join(tmp, "six_hours.csv")
    save(rec, path)
    t_copy = time.time()
    np.copy(rec.output)
    t_copy = time.time() - t_copy
    cmd = [sys.executable, "-c", "import sys, fogbayes.cli as c, fogbayes.cli.loop; "
           "sys.exit(c.main(sys.argv[1:]))", "loop", path, "--model", "bias-t",
           "--json", os.path.join(tmp, "loop.json"), "--compensated", os.path.join(tmp, "comp.csv")]
    t0 = time.time()
    subprocess.run(cmd, check=True, cwd=REPO)
    wall = time.time() - t0
    doc = json.load(open(os.path.join(tmp, "loop.json")))
    print(f"n = {rec.n} samples; fogbayes loop wall time {wall:.1f} s (fresh process, "
          f"JIT compile included); effects {[s['effect'] for s in doc['steps']]}; "
          f"memory copy of the output {t_copy * 1e3:.2f} ms; cores {os.cpu_count()}")


def _brief(res) -> str:
    """One paragraph per loop run: what was added (with its evidence) and why it stopped."""
    out = []
    for st in res.steps:
        e, d = st.evidence, st.detail
        keep = {k: v for k, v in d.items() if isinstance(v, (int, float, str))}
        out.append(f"+ {st.effect} {keep} 2dlogL={e['likelihood_ratio']:.3g} "
                   f"log10 p_fw={e['log10_p_familywise']:.3g} dELPD={e['elpd_diff']:.3g}"
                   f"+-{e['elpd_diff_se']:.3g} alternatives={[a['effect'] for a in e['alternatives']]}")
    b = res.stop.evidence or {}
    if b:
        out.append(f"stop: {res.stop.reason}; best remaining "
                   f"{b['refitted'][0]['effect'] if b.get('refitted') else '?'}; refitted: "
                   + ", ".join(f"{r['effect']} 2dlogL={r['likelihood_ratio']:.3g}"
                               for r in b.get("refitted", [])))
    out.append(f"RMS {res.initial.rms:.4g} -> {res.final.rms:.4g}; unexplained "
               f"{[u['kind'] for u in res.unexplained]}")
    return "\n    ".join(out)


def measured(args) -> None:
    import fogbayes  # noqa: F401
    from fogbayes.data import Metadata, Recording
    from fogbayes.loop import run_loop
    from fogbayes.thermal.pan_tvac import load_pan_tvac

    shared = os.environ.get("FOGBAYES_SHARED", os.path.join(os.path.dirname(__file__), "..", "..", "shared"))
    d = np.load(os.path.join(shared, "data/measured/adis16405_static_ucalgary/adis_16405_imu1.npz"))
    for j, name in enumerate(("gyro x", "gyro y", "gyro z")):
        x = d["data"][:, j]
        rec = Recording(time=np.arange(x.size) / 100.0, output=x, unit="deg/s",
                        meta=Metadata(sensor_id="adis16405-imu1", sample_rate=100.0))
        t0 = time.time()
        res = run_loop(rec, "allan", max_steps=3, seed=0)
        print(f"ADIS16405 imu1 {name} ({time.time() - t0:.0f} s):\n    {_brief(res)}", flush=True)
    pan = os.path.join(shared, "data/measured/pan_lsm6dsm_tvac_cold/TVCtest3_7_20.csv")
    for ax in "xyz":
        res = run_loop(load_pan_tvac(pan, ax), "bias-t", max_steps=3, seed=0)
        print(f"PAN TVAC {ax}: outliers {int(res.context.outlier.sum())}\n    {_brief(res)}",
              flush=True)


def _fixed_tau_fit(ctx, fit0, tau_c: float):
    """Profile log-likelihood with one Gauss-Markov component of known tau_c (variance and the
    other noise hyperparameters by maximum likelihood; Nelder-Mead from a few variance starts)."""
    from scipy import optimize

    from fogbayes.inference import noise_ssm as ns

    spec = fit0.noise.spec._replace(n_markov=1)
    lt = float(np.log(tau_c))

    def nll(x):
        th = np.concatenate([x, [lt]])
        return -float(ns.gls(spec, th, ctx.y, fit0.X, ctx.grid.mask, ctx.grid.w).loglik)

    best = None
    for lv in (-4.0, -1.0, 2.0):
        x0 = np.concatenate([fit0.noise.theta, [lv]])
        r = optimize.minimize(nll, x0, method="Nelder-Mead",
                              options={"xatol": 1e-3, "fatol": 1e-3, "maxiter": 600})
        if best is None or r.fun < best.fun:
            best = r
    return -best.fun


def markov_case(case: dict) -> dict:
    """Oracle and loop statistics of markov_noise on one record (see :func:`markov_info`)."""
    import fogbayes  # noqa: F401
    from fogbayes.loop import evidence as ev
    from fogbayes.loop.context import make_context
    from fogbayes.loop.fitting import fit_terms
    from fogbayes.loop.markov import refit_markov, screen_markov
    from fogbayes.loop.bases import base_terms

    tr = _record(case)
    ctx = make_context(tr.recording)
    fit0 = fit_terms(ctx, base_terms(ctx, "bias-t"))  # the true deterministic model
    oracle = 2.0 * (_fixed_tau_fit(ctx, fit0, 300.0) - fit0.loglik)
    wm, _ = ev.whitened_model(ctx, fit0, n_sims=50, seed=case["seed"])
    s = screen_markov(ctx, fit0, wm)
    alt = refit_markov(ctx, fit0, s)
    return dict(case, oracle_lr=max(oracle, 0.0), loop_lr=max(2.0 * (alt.loglik - fit0.loglik), 0.0))


def markov_info(args) -> None:
    """Is markov_noise at the study's sizes in the data at all? Likelihood ratios, paired records.

    For each configuration and seed, the same record with and without the planted Markov
    noise (the simulator draws it from its own seed stream, so the rest is identical):
    the oracle ratio (tau_c known = 300 s, variance and the other noise hyperparameters
    by ML, the true deterministic model) and the loop's refitted ratio (tau_c searched).
    The oracle bounds what any detector that knows tau_c can do at a given false-alarm rate.
    """
    seeds = range(args.seeds)
    todo = []
    for mag, noise, fs, dur, prof in CONFIGS:
        for sd in seeds:
            for eff in ("markov_noise", None):
                todo.append(dict(effect=eff, profile=prof, magnitude=mag, noise=noise, fs=fs,
                                 duration=float(dur), seed=sd))
    with ProcessPoolExecutor(args.workers) as pool:
        rows = list(pool.map(markov_case, todo))
    for mag, noise, fs, dur, prof in CONFIGS:
        g = [r for r in rows if r["noise"] == noise]
        for key in ("oracle_lr", "loop_lr"):
            h1 = np.array([r[key] for r in g if r["effect"]])
            h0 = np.array([r[key] for r in g if not r["effect"]])
            thr = np.quantile(h0, 0.95)
            print(f"{noise:8s} x{mag:g} {key:9s} H1 median {np.median(h1):6.1f} "
                  f"[{h1.min():.1f}, {h1.max():.1f}]  H0 median {np.median(h0):5.1f} "
                  f"max {h0.max():5.1f}; power at H0's 95 % point ({thr:.1f}): "
                  f"{np.mean(h1 > thr):.2f}; H1 > 13.4 (about the loop's family-wise 0.01): "
                  f"{np.mean(h1 > 13.4):.2f}")
            print(f"    H1 {np.round(np.sort(h1), 1).tolist()}  H0 {np.round(np.sort(h0), 1).tolist()}")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("what", choices=("study", "timing", "measured", "markov_info", "sweep",
                                        "detectability"))
    ap.add_argument("--seeds", type=int, default=6)
    ap.add_argument("--effects", default=None, help="comma-separated effect names (None = clean)")
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--noise", default=None, choices=("default", "flicker", "walk", "white"),
                    help="only the configuration with this noise mix (thermal records)")
    ap.add_argument("--first-seed", type=int, default=0,
                    help="study: seeds from here (fresh seeds test the method on unseen records)")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--out", default=DEFAULT_OUT)
    args = ap.parse_args()
    {"study": study, "timing": timing, "measured": measured,
     "markov_info": markov_info, "sweep": sweep,
     "detectability": detectability}[args.what](args)


if __name__ == "__main__":
    main()
