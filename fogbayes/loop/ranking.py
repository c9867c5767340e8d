"""Which of the supported candidates is added: ranking them against each other.

Supported = passes the rule alone. The best-ranked meets each other supported linear
candidate in the duel of :mod:`fogbayes.loop.compete`; where both are rejected, by
held-out prediction (:mod:`.holdout`; ``decided_by``). Indistinguishable ones go to
``evidence["alternatives"]``.
"""

from __future__ import annotations

import math

from .. import effects
from . import elpd as el
from . import evidence as ev
from .compete import Duel, duel
from . import holdout

#: Family-wise screening level a linear candidate must also reach.
SCREEN_GATE = 0.1
#: Effects a chamber programme can tell apart (``fogbayes plan-chamber``,
#: :mod:`fogbayes.plan.programme`): how fast and how long the chamber ramps and soaks.
PROGRAMME_SEPARABLE = frozenset(n for n, e in effects.REGISTRY.items() if e.separable_by_programme)


def separable_by_programme(chosen: str, alternative: str) -> bool:
    """Whether another chamber programme could decide a duel the data left undecided."""
    return all(n in effects.REGISTRY and effects.REGISTRY[n].separable_by_programme
               for n in (chosen, alternative))


def supported_trials(ctx, fit, trials, opts, n_cand: int, cache) -> list:
    """Every refitted candidate that passes the rule on its own, best-ranked first."""
    log_alpha = math.log(opts.alpha)
    out = []
    for tr in trials:
        if tr.log_p_fw >= log_alpha:
            break
        # The refitted ratio gains from re-estimating the noise, which the fixed-noise
        # bootstrap does not see: a candidate must also be suggestive (family-wise
        # p < SCREEN_GATE) in the calibrated screening itself -- under the fitted noise
        # model, not the second look without a random walk (core._screen_all), unless the
        # candidate's refit dropped the walk (core._trial then clears gate_log_p).
        s = tr.screened
        gate = s.log_p if s.gate_log_p is None else s.gate_log_p
        if ev.fw_log_p(gate, n_cand) >= math.log(SCREEN_GATE):
            continue
        d = el.compare(ctx, tr.fit, fit, seed=opts.seed, cache=cache)
        if d.diff > 0:
            out.append((tr, d))
    return out


def rank_supported(ctx, fit, supported, opts, step: int, cache: dict | None = None):
    """Candidates that explain the same residual, ranked against each other (:mod:`compete`).

    The best-ranked supported candidate meets every other supported linear candidate in a
    bootstrap-calibrated duel; the winner of each duel goes on. Returns the chosen
    (trial, elpd difference) and the duels [(leader, other, Duel)].
    """
    champ = supported[0]
    duels = []
    for other in supported[1:]:
        if champ[0].screened.candidate.kind != "linear" or \
                other[0].screened.candidate.kind != "linear":
            continue
        du = duel(ctx, fit, (champ[0].screened, champ[0].fit), (other[0].screened, other[0].fit),
                  n_sims=opts.n_sims, seed=opts.seed + 104729 * (step + 1), cache=cache)
        if du is None:
            continue
        if du.verdict == "neither alone":
            du = by_holdout(ctx, champ[0], other[0], du)
        duels.append((champ, other, du))
        if du.winner == "B":
            champ = other
    return champ, duels


def by_holdout(ctx, a, b, du: Duel) -> Duel:
    """Neither candidate alone accounts for the residual: keep the one whose model predicts
    held-out time blocks better, a step's time averaged over its grid as the training
    blocks weigh it (:mod:`fogbayes.loop.holdout_search`). The in-sample likelihood would
    favour the more flexible one: a step searched at every block boundary follows the noise."""
    lpd = [holdout.score(ctx, t.fit,
                         search=holdout.searched_columns(ctx, t.screened.candidate, t.fit)).lpd
           for t in (a, b)]
    return du._replace(winner="B" if lpd[1] > lpd[0] else "A", lpd=(lpd[0], lpd[1]))


def duel_json(a, b, du: Duel) -> dict:
    return {"leader": a[0].screened.candidate.effect, "other": b[0].screened.candidate.effect,
            "d_2loglik_other_minus_leader": du.d_obs, "p_leader": du.p_a, "p_other": du.p_b,
            "verdict": du.verdict, "winner": (a if du.winner == "A" else b)[0].screened.candidate.effect,
            "n_sims": du.n_sims,
            **({} if du.lpd is None else {"decided_by": "held-out log predictive density",
                                          "lpd_leader": du.lpd[0], "lpd_other": du.lpd[1]})}


def alternatives(ctx, chosen, duels, opts, cache) -> list[dict]:
    """Candidates the data cannot tell from the chosen one (duel verdict "indistinguishable").

    Each is reported with the duel's numbers and the PSIS-LOO difference of the two refitted
    models (chosen minus alternative, with its standard error): the issue's |d elpd| < 2 se
    reading, shown beside the bootstrap that also accounts for searched parameters.
    """
    out = []
    for a, b, du in duels:
        if du.verdict != "indistinguishable" or not (a[0] is chosen or b[0] is chosen):
            continue
        alt = b if a[0] is chosen else a
        d = el.compare(ctx, chosen.fit, alt[0].fit, seed=opts.seed, cache=cache)
        effect = alt[0].screened.candidate.effect
        out.append({"effect": effect,
                    "separable_by_programme": separable_by_programme(
                        chosen.screened.candidate.effect, effect),
                    "likelihood_ratio": alt[0].lr,
                    "searched": alt[0].screened.candidate.searched,
                    "d_2loglik_alternative_minus_chosen": du.d_obs if a[0] is chosen else -du.d_obs,
                    "p_chosen": du.p_a if a[0] is chosen else du.p_b,
                    "p_alternative": du.p_b if a[0] is chosen else du.p_a,
                    "elpd_diff_chosen_minus_alternative": d.diff, "elpd_diff_se": d.se,
                    "note": "indistinguishable by the bootstrap duel; the simpler (fewer "
                            "searched parameters) or better-ranked one was kept"})
    return out
