"""Which chamber programme lets the loop tell two thermal effects apart.

In the whitened GLS space of the base model, z = mu + e, D(z) = max_a (u_a'z)^2 - max_b (u_b'z)^2
(the duel of :mod:`fogbayes.loop.compete`); power = P(B rejected | A) by Monte Carlo on the
span of the columns; noncentrality lambda = min_b ||(I - P_b) mu||^2 ranks programmes. Programmes
are Soak/Ramp cycles (:mod:`fogbayes.simulate.profiles`) seen through first-order ``lags``.
"""

from __future__ import annotations

from typing import NamedTuple, Sequence

import numpy as np

from ..loop.context import make_context
from ..loop.evidence import whiten_columns
from ..effects import REGISTRY
from ..effects.terms import Term
from ..loop.bases import base_terms
from ..simulate.profiles import Ramp, Soak, segments_json, thermal_test_segments

#: Ramp rates (deg C/min) and soak lengths (s) of the searched cycles.
RATES = (0.5, 1.0, 2.0, 3.0, 5.0, 10.0)
SOAKS = (900.0, 1800.0, 2700.0, 3600.0, 5400.0, 7200.0)
#: Searched lag time constants: the loop's range, 4x finer (stands in for its refinement).
N_TAUS = 48


class Pair(NamedTuple):
    """A true effect and the rival the loop might take instead (names in
    :data:`fogbayes.effects.REGISTRY`)."""

    truth: str
    rival: str
    coeff: float      # true coefficient in the truth's unit (e.g. deg/h per deg C for a lag)
    tau: float | None = None  # the truth's time constant (s) when it has a searched one

    @property
    def label(self) -> str:
        t = f"{self.truth} (tau {self.tau:g} s)" if self.tau else self.truth
        return f"{t} vs {self.rival}"


def rivals(name: str) -> list[str]:
    """The effects a programme must tell ``name`` from: the other registered effects marked
    ``separable_by_programme``, the latest registered first."""
    return [n for n, fx in reversed(REGISTRY.items()) if fx.separable_by_programme and n != name]


def pairs_for(truths: dict) -> list[Pair]:
    """Each true effect against each of its :func:`rivals`. ``truths``: effect name ->
    (true coefficient, true time constants), ``[None]`` for an effect without one."""
    return [Pair(name, rival, coeff, tau) for name, (coeff, taus) in truths.items()
            for rival in rivals(name) for tau in taus]


class Score(NamedTuple):
    """One programme's ability to separate each pair."""

    name: str
    segments: list
    noncentrality: dict   # pair label -> lambda
    power: dict           # pair label -> P(rival rejected), Monte Carlo (None: not computed)

    @property
    def worst(self) -> float:
        return min(self.noncentrality.values())


def cycling(rate: float, soak: float, *, duration: float, low: float = -20.0,
            high: float = 60.0, room: float = 20.0, first_soak: float = 600.0) -> list:
    """Soak at room, then ramp to high, soak, ramp to low, soak, ... until ``duration`` s."""
    segs, T, t, k = [Soak(room, first_soak)], room, first_soak, 0
    while t < duration:
        to = (high, low)[k % 2]
        k += 1
        segs.append(Ramp(to, rate))
        t += abs(to - T) / rate * 60.0
        T = to
        segs.append(Soak(T, soak))
        t += soak
    return segs


def candidates(*, duration: float, low: float, high: float, room: float,
               max_rate: float) -> dict[str, list]:
    """The generic test and every cycle of :data:`RATES` (<= ``max_rate``) x :data:`SOAKS`."""
    out = {"generic test": thermal_test_segments(duration=duration, room=room, low=low,
                                                 high=high)}
    for r in RATES:
        if r > max_rate + 1e-12:
            continue
        for s in SOAKS:
            if s < 0.5 * duration:
                out[f"cycle {r:g} deg C/min, soak {s / 60:g} min"] = cycling(
                    r, s, duration=duration, low=low, high=high, room=room)
    return out


def design_record(segments, *, duration: float, fs: float, lags: Sequence[float], room: float):
    """A noise-free record of the programme (only its covariates are used)."""
    from ..simulate.scenarios import simulate

    return simulate("thermal", seed=0, fs=fs, duration=duration, noise={}, segments=segments,
                    lags=tuple(lags), room=room).recording


def _columns(ctx, pairs: Sequence[Pair]) -> tuple[np.ndarray, dict]:
    """Block columns of the base model, each effect's family
    (:meth:`~fogbayes.effects.Effect.programme_terms`) and each true effect."""
    base = base_terms(ctx, "bias-t")
    names = dict.fromkeys(n for p in pairs for n in (p.truth, p.rival))
    fam = {n: REGISTRY[n].programme_terms(ctx, N_TAUS) for n in names}
    truth = {p.label: REGISTRY[p.truth].programme_terms(
        ctx, N_TAUS, None if p.tau is None else {"tau": p.tau})[0] for p in pairs}
    blocks, index = [ctx.block_design(base)], {}
    at = blocks[0].shape[1]
    for name, terms in list(fam.items()) + [(k, [v]) for k, v in truth.items()]:
        blocks.append(ctx.block_design(terms))
        index[name] = np.arange(at, at + len(terms))
        at += len(terms)
    return np.column_stack(blocks), {"n_base": blocks[0].shape[1], **index}


def _residualised(ctx, noise, X: np.ndarray, n_base: int) -> np.ndarray:
    """Whitened columns with the whitened base model projected out, in units of sigma."""
    W = whiten_columns(ctx, noise.spec, noise.theta, X) / np.sqrt(noise.sigma2)
    Q, _ = np.linalg.qr(W[:, :n_base])
    R = W[:, n_base:]
    return R - Q @ (Q.T @ R)


def _unit(R: np.ndarray) -> np.ndarray:
    return R / np.maximum(np.linalg.norm(R, axis=0), 1e-300)


def noncentrality(mu: np.ndarray, rival: np.ndarray) -> float:
    """min over the rival's members b of ||(I - P_b) mu||^2."""
    proj = (_unit(rival).T @ mu) ** 2
    return float(mu @ mu - proj.max())


def duel_power(mu: np.ndarray, own: np.ndarray, rival: np.ndarray, *, alpha: float = 0.05,
               draws: int = 400, boot: int = 400, seed: int = 0) -> float:
    """P(the duel rejects the rival) when z = mu + e (module doc), by Monte Carlo."""
    rng = np.random.default_rng(seed)
    R = np.column_stack([own, rival, mu])
    U, sv, _ = np.linalg.svd(R, full_matrices=False)
    U = U[:, sv > 1e-9 * sv[0]]
    A, B = U.T @ _unit(own), U.T @ _unit(rival)
    m, k = U.T @ mu, U.shape[1]

    def stat(z):
        return ((z @ A) ** 2).max(-1) - ((z @ B) ** 2).max(-1)

    z = m + rng.standard_normal((draws, k))
    d = stat(z)
    pz = z @ B
    best = np.argmax(pz ** 2, axis=1)
    centre = pz[np.arange(draws), best][:, None] * B[:, best].T  # (draws, k)
    p = np.empty(draws)
    for i in range(draws):  # one bootstrap of the rival's null per draw
        p[i] = np.mean(stat(centre[i] + rng.standard_normal((boot, k))) >= d[i])
    return float(np.mean(p < alpha))


def score(name: str, segments, pairs: Sequence[Pair], noise, *, duration: float, fs: float,
          lags: Sequence[float], room: float, power: bool = False, seed: int = 0) -> Score:
    """Noncentrality (and optionally duel power) of every pair under one programme."""
    ctx = make_context(design_record(segments, duration=duration, fs=fs, lags=lags, room=room),
                       flag_outliers=False)
    if ctx.grid.dt != noise_dt(noise):
        raise ValueError(f"the noise model's blocks are {noise_dt(noise):g} s, this "
                         f"programme's {ctx.grid.dt:g} s: plan at the noise record's length")
    X, ix = _columns(ctx, pairs)
    R = _residualised(ctx, noise, X, ix["n_base"])
    off = ix["n_base"]
    col = lambda key: R[:, ix[key] - off]
    lam, pw = {}, {}
    for p in pairs:
        mu = p.coeff * col(p.label)[:, 0]
        lam[p.label] = noncentrality(mu, col(p.rival))
        # a searched time constant may fall between the family's grid: the truth joins it
        own = np.column_stack([col(p.truth), mu[:, None]]) if p.tau is not None \
            else col(p.truth)
        pw[p.label] = duel_power(mu, own, col(p.rival), seed=seed) if power else None
    return Score(name, segments_json(segments), lam, pw)


def noise_dt(noise) -> float:
    return float(noise.spec.dt)


def noise_for_plan(recording=None, *, allan: dict | None = None, duration: float | None = None,
                   fs: float | None = None, lags: Sequence[float] = (300.0, 900.0),
                   room: float = 20.0, seed: int = 0):
    """The noise model the plan whitens with: fitted as the loop fits it (GLS + ML noise on
    block means, base bias-t model plus the gradient when there are two channels).

    From a pilot ``recording`` of the chamber (its length and rate are then the plan's), or,
    without one, from Allan terms ``allan`` (N, B, K in deg/sqrt(h), deg/h, deg/h^1.5) on one
    record of ``duration`` s at ``fs`` Hz simulated under the generic test (seeded).
    """
    from ..loop.fitting import fit_terms

    if recording is None:
        from ..simulate.scenarios import simulate

        recording = simulate("thermal", seed=seed, fs=fs, duration=duration, noise=dict(allan),
                             lags=tuple(lags), room=room).recording
    ctx = make_context(recording)
    terms = base_terms(ctx, "bias-t")
    if ctx.cov.n_temps >= 2:
        terms.append(Term("gradient", {"a": 0, "b": 1, "scale": 1.0}))
    fs = float(recording.sample_rate)
    return fit_terms(ctx, terms, residual=False).noise, recording.n / fs, fs


class ChamberPlan(NamedTuple):
    """The best programme found, the baseline, and every candidate's score."""

    best: Score
    baseline: Score
    scores: list
    pairs: list
    settings: dict

    def to_json(self) -> dict:
        row = lambda s: {"name": s.name, "segments": s.segments,
                         "noncentrality": s.noncentrality, "power": s.power}
        return {"schema": "fogbayes.plan_chamber/1", "settings": self.settings,
                "pairs": [p._asdict() | {"label": p.label} for p in self.pairs],
                "best": row(self.best), "baseline": row(self.baseline),
                "candidates": [{"name": s.name, "worst_noncentrality": s.worst}
                               for s in self.scores]}


def plan_programme(noise, pairs: Sequence[Pair], *, duration: float, fs: float,
                   lags: Sequence[float] = (300.0, 900.0), low: float = -20.0,
                   high: float = 60.0, room: float = 20.0, max_rate: float = 5.0,
                   baseline: list | None = None, seed: int = 0) -> ChamberPlan:
    """Score every candidate cycle; the best maximises the worst pair's noncentrality.

    ``noise``: a :class:`~fogbayes.inference.noise_ssm.NoiseFit` on blocks of a record of
    this ``duration`` and ``fs`` (:func:`noise_for_plan`);
    ``baseline``: the programme to compare with (default: the generic test).
    """
    kw = dict(duration=duration, fs=fs, lags=lags, room=room)
    progs = candidates(duration=duration, low=low, high=high, room=room, max_rate=max_rate)
    base_name, base_segs = "generic test", progs.pop("generic test")
    if baseline is not None:
        base_name, base_segs = "your programme", baseline
    if not progs:
        raise ValueError(f"no candidate programme: ramps of at most {max_rate:g} deg C/min "
                         f"and soaks shorter than half of {duration:g} s")
    scores = [score(n, s, pairs, noise, **kw) for n, s in progs.items()]
    best = max(scores, key=lambda s: s.worst)
    # the baseline is only compared with (it may break --max-rate: the generic test's ramps
    # are sized to the record); the duel's power is simulated for the two shown
    before = score(base_name, base_segs, pairs, noise, power=True, seed=seed, **kw)
    best = score(best.name, progs[best.name], pairs, noise, power=True, seed=seed, **kw)
    settings = dict(duration_s=duration, fs_hz=fs, lags_s=list(lags), low=low, high=high,
                    room=room, max_rate_deg_c_per_min=max_rate, alpha=0.05,
                    rule="max over programmes of min over pairs of the noncentrality")
    return ChamberPlan(best, before, sorted(scores, key=lambda s: -s.worst), list(pairs),
                       settings)
