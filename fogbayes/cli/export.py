"""``fogbayes export DOC... --format F --out FILE``: numbers for filters and firmware.

``kalibr`` (:func:`fogbayes.export.noise.kalibr_yaml`), ``ieee952``
(:func:`fogbayes.export.noise.ieee952_document`), ``px4`` / ``ardupilot`` (one per axis, x, y, z;
:mod:`fogbayes.export.coefficients`). Units: docs/units.md.
"""

from __future__ import annotations

from pathlib import Path

import typer

from ._app import app
from ._common import QUIET_OPT, refuse_overwrite, say

_FORMATS = ("kalibr", "ieee952", "px4", "ardupilot")


def _ordered(paths: list[Path]) -> list[tuple[dict, str]]:
    """The documents in x, y, z order: plain documents in the order given; the axes of a
    multi-axis document by their names (x, y, z from the start, none missing or repeated)."""
    from ..data.axes_doc import per_axis
    from ..data.documents import read_calibration
    from ..export.coefficients import ExportError

    named = [(name, doc, where) for p in paths
             for name, doc, where in per_axis(read_calibration(p), str(p))]
    names = [n for n, _, _ in named]
    if all(n is None for n in names):
        return [(doc, where) for _, doc, where in named]
    if any(n is None for n in names) or sorted(names) != list("xyz"[:len(names)]):
        raise ExportError(f"the firmware takes the gyro axes as x, y, z; the documents hold "
                          f"axes {[n or '(unnamed)' for n in names]}", file=str(paths[0]),
                          field="axes", fix="fit the axes x, y, z (or x, or x and y) into one "
                                             "document ('fogbayes fit LOG --axis all'), or pass "
                                             "one plain document per axis in x, y, z order")
    return [(doc, where) for n in "xyz"[:len(names)] for m, doc, where in named if m == n]


def _axes(paths: list[Path]) -> tuple[list, tuple[float, float] | None, list[str]]:
    """(basis, coef) per axis from bias-t fit or loop documents, in x, y, z order; the
    temperature span the fits saw (None when no document states one); the documents'
    warnings about the logged rates (fogbayes/data/logs/firmware.py)."""
    from ..errors import FogbayesError
    from ..export.coefficients import ExportError, basis_from_loop
    from ..models.basis_document import basis_from_dict

    from ..data.logs.firmware import PREFIX as FIRMWARE_PREFIX

    axes, spans, notes = [], [], []
    for doc, p in _ordered(paths):
        if doc.get("schema", "").startswith("fogbayes.loop"):
            axes.append(basis_from_loop(doc, source=p))
            rng = doc["calibration"].get("valid", {}).get("temperature")
            spans.append(rng[0] if isinstance(rng, list) and rng and isinstance(rng[0], list)
                         else None)
            continue
        if doc.get("model") != "bias-t":
            raise ExportError(f"firmware thermal parameters come from a bias-t fit, this is a "
                              f"{doc.get('model')!r} document", file=p, field="model",
                              fix="run 'fogbayes fit REC --model bias-t --orders 3' (temperature only)")
        params = doc["params"]
        unit = (params.get("units") or {}).get("output", "deg/h")
        if unit != "deg/h":
            raise FogbayesError(f"the fit's output unit is {unit!r}, the export needs deg/h",
                                file=p, field="params.units.output",
                                fix="run 'fogbayes fit' with --output-unit set to the recording's rate unit")
        axes.append((basis_from_dict(params["basis"], source=p), params["coef"]))
        spans.append((params.get("valid_range") or {}).get("T"))
        notes.extend(f"{p}: {w}" for w in doc.get("warnings") or []
                     if w.startswith(FIRMWARE_PREFIX))
    spans = [sp for sp in spans if sp is not None]
    # the span of the data the fits saw (else: the bases' centre +- scale)
    span = (min(sp[0] for sp in spans), max(sp[1] for sp in spans)) if spans else None
    return axes, span, notes


@app.command()
def export(
    docs: list[Path] = typer.Argument(..., help="Allan documents, one per axis or one of "
                                                "'fogbayes allan --axis all' (kalibr, ieee952), "
                                                "or bias-t "
                                                "fit / loop documents (px4, ardupilot), one "
                                                "per axis in x, y, z order.",
                                      show_default=False),
    fmt: str = typer.Option(..., "--format", "-f", help="kalibr | ieee952 | px4 | ardupilot."),
    out: str = typer.Option(..., "--out", help="File to write ('-' = stdout)."),
    quantile: float = typer.Option(0.5, help="kalibr: which quantile of N and K to write: 0.5 "
                                             "the estimate, 0.05 / 0.95 the 90 % interval's "
                                             "ends."),
    topic: str = typer.Option("/imu0", help="kalibr: the IMU topic written as 'rostopic'."),
    index: int = typer.Option(None, help="px4: gyro index i of TC_G<i>_* (default 0); "
                                         "ardupilot: IMU number i of INS_TCAL<i>_* (default 1)."),
    device_id: int = typer.Option(0, help="px4: TC_G<i>_ID, the gyro's device id."),
    quiet: bool = QUIET_OPT,
):
    """Write filter- or firmware-ready numbers from fogbayes documents.

    Units and formulas (continuous vs discrete time, IEEE 952 names): docs/units.md.

    Examples:
      fogbayes export adev.json --format kalibr --out imu.yaml
      fogbayes export adev_x.json adev_y.json adev_z.json -f kalibr --quantile 0.95 --out imu.yaml
      fogbayes export fit_x.json fit_y.json fit_z.json -f ardupilot --out tcal.param
    """
    import json

    from ..data.atomic import write_text
    from ..data.documents import read_calibration
    from ..errors import FogbayesError

    if fmt not in _FORMATS:
        raise FogbayesError(f"unknown export format '{fmt}'", column="--format",
                            fix=f"use one of {', '.join(_FORMATS)}")
    if quantile != 0.5 and fmt != "kalibr":
        raise FogbayesError(f"--quantile applies to --format kalibr, not {fmt}",
                            column="--quantile", fix="drop --quantile (ieee952 writes the "
                                                     "estimate and both interval ends)")
    ranges = {"px4": (0, 3), "ardupilot": (1, 3)}  # TC_G0..3_*, INS_TCAL1..3_*
    if index is not None and (fmt not in ranges or not ranges[fmt][0] <= index <= ranges[fmt][1]):
        lo, hi = ranges.get(fmt, (None, None))
        raise FogbayesError(f"--index {index} names no {fmt} parameter set", column="--index",
                            fix=f"use {lo}..{hi}" if lo is not None else
                                "drop --index (px4 and ardupilot only)")
    refuse_overwrite({"a document": docs}, {"--out": out})
    if fmt in ("kalibr", "ieee952"):
        from ..export.noise import ieee952_document, kalibr_yaml

        from ..data.axes_doc import per_axis

        # a multi-axis document (fogbayes allan --axis all) counts as one document per axis
        named = [row for p in docs for row in per_axis(read_calibration(p), str(p))]
        if fmt == "ieee952":
            if len(docs) != 1:
                raise FogbayesError(f"ieee952 takes one Allan document, got {len(docs)}",
                                    column="DOCS", fix="export each file on its own")
            parts = {name: ieee952_document(sub, source=where) for name, sub, where in named}
            out_doc = parts[None] if None in parts else \
                {"schema": "fogbayes.ieee952/1", "axes": parts}
            text = json.dumps(out_doc, indent=2) + "\n"
        else:
            text = kalibr_yaml([(sub, where) for _, sub, where in named], quantile=quantile,
                               topic=topic)
    else:
        from ..export import coefficients as ex

        axes, span, notes = _axes(docs)
        if len(axes) > 3:
            raise FogbayesError(f"{fmt} takes 1 to 3 axes, got {len(axes)}", column="DOCS",
                                fix="pass the x, y, z documents in that order")
        if fmt == "px4":
            params = ex.px4_gyro_parameters(axes, gyro_index=0 if index is None else index,
                                            device_id=device_id, t_range=span)
            text = ex.px4_param_file(params)
        else:
            params = ex.ardupilot_gyro_parameters(axes, imu_index=1 if index is None else index,
                                                  t_range=span)
            text = ex.ardupilot_param_file(params)
        for note in notes:  # in the file and on the screen: the log's rates were not raw
            say(f"warning: {note}")
        text = "".join(f"# warning: {n}\n" for n in notes) + text
    if out == "-":
        typer.echo(text, nl=False)
    else:
        write_text(out, text)
        say(f"wrote {out} ({fmt})")
