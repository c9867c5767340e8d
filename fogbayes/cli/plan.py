"""``fogbayes plan PILOT --term K --precision 0.10``: how long to record a static run.

Wires :func:`fogbayes.plan.pilot.plan_recording`: the length whose GLS fit gives the term a
relative half-width of ``--precision`` at ``--level``, with the range the pilot allows
(docs/plan.md); ``--json`` writes the plan document.
"""

from __future__ import annotations

import sys
from pathlib import Path

import typer

from ._app import app
from ._common import (QUIET_OPT, REC_ARG, TIME_UNIT_OPT, channels, load_recording, progress,
                      reading_options, refuse_overwrite, say, write_json)


_FLAGS = {"term": "--term", "terms": "--terms", "precision": "--precision", "level": "--level",
          "max_days": "--max-days"}


@app.command()
def plan(
    pilot: Path = REC_ARG,
    term: str = typer.Option(..., "--term", help="Noise term to plan for: N, B or K "
                                                 "(also Q or R)."),
    precision: float = typer.Option(..., "--precision",
                                    help="Target relative half-width of the term's interval: "
                                         "0.10 = +-10 %."),
    level: float = typer.Option(0.9, "--level", help="Two-sided confidence of that interval."),
    max_days: float = typer.Option(1000.0, "--max-days",
                                   help="Refuse a plan longer than this many days."),
    terms: str = typer.Option("Q,N,B,K,R", "--terms",
                              help="Candidate terms of the pilot's model (unresolved ones are "
                                   "dropped); e.g. Q,N,B,K when the rate has no ramp."),
    json_out: str = typer.Option(None, "--json",
                                 help="Also write the plan document ('-' = stdout)."),
    time_unit: str = TIME_UNIT_OPT,
    quiet: bool = QUIET_OPT,
):
    """How long must a static run be to know a noise term to +-x %? Planned from a pilot.

    The pilot's noise terms are fitted (GLS on octave taus, the terms it resolves); the length is the shortest record whose fit would give the term a relative half-width (high - low) / (2 value) of at most --precision at --level, from the Fisher information of the octave Allan variances. The range is the shortest and the longest plan over the pilot's joint 90 % uncertainty of the noise values: a short pilot knows K poorly, and so the length K needs (docs/plan.md).

    Examples:
      fogbayes plan pilot_1h.csv --term K --precision 0.10
      fogbayes plan pilot.csv --term N --precision 0.01 --level 0.95 --json plan.json
      fogbayes -q plan pilot.csv --term B --precision 0.05 --json - > plan.json
    """
    from ..errors import FogbayesError, about_file
    from ..allan.model import TERMS
    from ..plan.length import PlanError, _validate
    from ..plan.pilot import plan_recording, summary_lines

    refuse_overwrite({"the pilot recording": pilot}, {"--json": json_out})
    name = term.strip().upper()
    if name not in TERMS:
        raise FogbayesError(f"unknown term '{term}'", column="--term",
                            fix=f"use one of {', '.join(TERMS)} (e.g. --term K)")
    try:
        _validate(name, precision, level, max_days)
    except FogbayesError as exc:
        raise FogbayesError(exc.problem, column=_FLAGS.get(exc.column or "", exc.column),
                            fix=exc.fix) from None
    model = [t.strip().upper() for t in terms.split(",") if t.strip()]
    bad = [t for t in model if t not in TERMS]
    if bad or not model or name not in model:
        raise FogbayesError(f"--terms {terms!r} must name terms among {', '.join(TERMS)} and "
                            f"include --term {name}", column="--terms",
                            fix=f"give e.g. --terms Q,N,B,K (with {name})")
    picks = channels(*(reading_options()[k] for k in ("axis", "column")))
    if len(picks) > 1:
        raise FogbayesError("plan reads one channel at a time", column="--axis/--column",
                            fix="give one axis (--axis x) or one column, and run plan per axis")
    rec = load_recording(pilot, time_unit=time_unit, **picks[0][1])
    try:
        with progress("Fitting the pilot and planning"), about_file(pilot):
            doc = plan_recording(rec, name, precision, level=level, max_days=max_days,
                                 terms=tuple(model))
    except PlanError as exc:  # name the command-line flag, not the function's keyword
        flag = _FLAGS.get(exc.column or "", exc.column)
        raise PlanError(exc.problem, file=exc.file or str(pilot), column=flag,
                        fix=exc.fix) from None
    lines = summary_lines(doc)
    if json_out is None:
        sys.stdout.write("\n".join(lines) + "\n")  # the result itself: on stdout
        return
    write_json(doc, json_out)
    for line in lines:
        say(line)
