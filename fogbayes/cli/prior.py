"""``fogbayes prior --arw ... --bias-instability ... [--rrw ...] --json PRIOR.json``: a datasheet prior.

Wires :func:`fogbayes.inference.datasheet.build_prior` (docs/priors.md): the ``fogbayes.prior/1``
document read by ``allan --bayes --prior`` and ``loop --noise-prior``.
"""

from __future__ import annotations

import typer

from ._app import app
from ._common import QUIET_OPT, refuse_overwrite, say, write_json

_SHEET = "Datasheet values"


@app.command(name="prior")
def prior(
    json_out: str = typer.Option(..., "--json", help="Prior document to write ('-' = stdout)."),
    arw: float = typer.Option(None, "--arw", help="Angle random walk (ARW).",
                              rich_help_panel=_SHEET, show_default=False),
    arw_unit: str = typer.Option("deg/sqrt(h)", "--arw-unit",
                                 help="deg/sqrt(h), deg/h/sqrt(Hz), deg/s/sqrt(Hz), "
                                      "deg/sqrt(s), mdeg/s/sqrt(Hz), rad/s/sqrt(Hz), "
                                      "rad/sqrt(s), mrad/sqrt(h).",
                                 rich_help_panel=_SHEET),
    bias_instability: float = typer.Option(None, "--bias-instability",
                                           help="Bias instability (by default the ADEV "
                                                "floor, = 0.664 B).",
                                           rich_help_panel=_SHEET, show_default=False),
    bias_instability_unit: str = typer.Option("deg/h", "--bias-instability-unit",
                                              help="deg/h, deg/s, mdeg/s, rad/s, urad/s.",
                                              rich_help_panel=_SHEET),
    bias_instability_is: str = typer.Option("adev-floor", "--bias-instability-is",
                                            help="adev-floor: the ADEV minimum (the usual "
                                                 "datasheet number; B = value / 0.6643); B: "
                                                 "the flicker coefficient itself.",
                                            rich_help_panel=_SHEET),
    rrw: float = typer.Option(None, "--rrw", help="Rate random walk (RRW), if the sheet "
                                                  "gives it.",
                              rich_help_panel=_SHEET, show_default=False),
    rrw_unit: str = typer.Option("deg/h/sqrt(h)", "--rrw-unit",
                                 help="deg/h/sqrt(h) (= deg/h^1.5), deg/h/sqrt(s), "
                                      "deg/s/sqrt(h), deg/s/sqrt(s), deg/s^2/sqrt(Hz), "
                                      "deg/h^2/sqrt(Hz), rad/s/sqrt(s), rad/s^2/sqrt(Hz).",
                                 rich_help_panel=_SHEET),
    looseness: float = typer.Option(3.0, "--looseness",
                                    help="The true value lies within a factor LOOSENESS of "
                                         "the sheet's with 90 % prior probability (> 1)."),
    sensor: str = typer.Option(None, "--sensor", help="Sensor name, recorded in the document.",
                               show_default=False),
    quiet: bool = QUIET_OPT,
):
    """Write a prior document from a gyro datasheet (ARW, bias instability, RRW).

    Each value the sheet gives becomes a log-normal prior centred at it, in canonical units (N deg/sqrt(h), B deg/h, K deg/h^1.5); terms the sheet does not give keep the default half-normal prior. A datasheet's bias instability is usually the ADEV floor, 0.664 B: it is converted to B unless --bias-instability-is B. Quote units with parentheses in the shell ('deg/h/sqrt(Hz)'). Units table: docs/priors.md.

    Examples:
      fogbayes prior --arw 0.05 --bias-instability 0.5 --sensor "KVH 1750" \\
          --json sheet.json
      fogbayes prior --arw 0.15 --arw-unit 'deg/h/sqrt(Hz)' \\
          --bias-instability 0.05 --rrw 0.02 --looseness 2 --json sheet.json
      fogbayes allan short.csv --bayes --prior sheet.json --json av.json
      fogbayes loop chamber.csv -m bias-t --noise-prior sheet.json \\
          --json loop.json --compensated comp.csv
    """
    from ..inference.datasheet import build_prior
    from ..allan.model import UNITS

    refuse_overwrite({}, {"--json": json_out})
    sheet = build_prior(arw=arw, arw_unit=arw_unit, bias_instability=bias_instability,
                        bias_instability_unit=bias_instability_unit,
                        bias_instability_is=bias_instability_is, rrw=rrw, rrw_unit=rrw_unit,
                        looseness=looseness, sensor=sensor)
    write_json(sheet.to_doc(), json_out)
    for t, p in sheet.terms.items():
        d = p.datasheet
        lo, hi = p.range90
        say(f"{t} = {p.value:.4g} {UNITS[t]} (from {d['quantity']} {d['value']:g} {d['unit']}"
            + (", ADEV floor / 0.6643" if d.get("convention", "").startswith("ADEV") else "")
            + f"), 90 % prior range [{lo:.4g}, {hi:.4g}]")
    if "K" not in sheet.terms:
        say("no RRW on the sheet: K keeps the half-normal prior, and 'fogbayes loop "
            "--noise-prior' refuses this document (it caps nothing)")
