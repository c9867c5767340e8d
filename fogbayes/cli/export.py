"""``fogbayes export DOC... --format F --out FILE``: numbers for filters and firmware.

* ``kalibr``: Kalibr/OpenVINS ``imu.yaml`` gyroscope keys from Allan documents
  (:func:`fogbayes.export_noise.kalibr_yaml`);
* ``ieee952``: the five IEEE 952 terms with intervals, in document units and SI
  (:func:`fogbayes.export_noise.ieee952_document`);
* ``px4`` / ``ardupilot``: ``TC_G*`` / ``INS_TCAL*`` parameter files from ``bias-t`` fit
  documents or loop calibrations, one per axis in x, y, z order (:mod:`fogbayes.export`).

The unit table is ``docs/units.md``.
"""

from __future__ import annotations

from pathlib import Path

import typer

from ._app import app
from ._common import QUIET_OPT, refuse_overwrite, say

_FORMATS = ("kalibr", "ieee952", "px4", "ardupilot")


def _axes(paths: list[Path]) -> tuple[list, tuple[float, float] | None]:
    """(basis, coef) per axis from bias-t fit or loop documents, and their temperature span."""
    from ..data.documents import read_calibration
    from ..errors import FogbayesError
    from ..export import ExportError, basis_from_dict, basis_from_loop

    from ..data.axes_doc import per_axis

    axes, spans = [], []
    # a multi-axis document (fogbayes fit --axis all) counts as one document per axis
    for doc, p in ((sub, where) for p in paths
                   for _, sub, where in per_axis(read_calibration(p), str(p))):
        if doc.get("schema", "").startswith("fogbayes.loop"):
            axes.append(basis_from_loop(doc, source=str(p)))
            rng = doc["calibration"].get("valid", {}).get("temperature")
            spans.append(rng[0] if isinstance(rng, list) and rng and isinstance(rng[0], list)
                         else None)
            continue
        if doc.get("model") != "bias-t":
            raise ExportError(f"firmware thermal parameters come from a bias-t fit, this is a "
                              f"{doc.get('model')!r} document", file=str(p), column="model",
                              fix="run 'fogbayes fit REC --model bias-t --orders 3' (temperature only)")
        params = doc["params"]
        unit = (params.get("units") or {}).get("output", "deg/h")
        if unit != "deg/h":
            raise FogbayesError(f"the fit's output unit is {unit!r}, the export needs deg/h",
                                file=str(p), column="params.units.output",
                                fix="run 'fogbayes fit' with --output-unit set to the recording's rate unit")
        axes.append((basis_from_dict(params["basis"], source=str(p)), params["coef"]))
        spans.append((params.get("valid_range") or {}).get("T"))
    if all(s is not None for s in spans):
        return axes, (min(s[0] for s in spans), max(s[1] for s in spans))
    return axes, None


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
    refuse_overwrite({"a document": docs}, {"--out": out})
    if fmt in ("kalibr", "ieee952"):
        from ..export_noise import ieee952_document, kalibr_yaml

        from ..data.axes_doc import per_axis

        # a multi-axis document (fogbayes allan --axis all) counts as one document per axis
        loaded = [(sub, where) for p in docs
                  for _, sub, where in per_axis(read_calibration(p), str(p))]
        if fmt == "ieee952":
            if len(docs) != 1:
                raise FogbayesError(f"ieee952 takes one Allan document, got {len(docs)}",
                                    column="DOCS", fix="export each file on its own")
            names = [name for name, _, _ in per_axis(read_calibration(docs[0]))]
            out_doc = ieee952_document(*loaded[0][:1], source=loaded[0][1]) \
                if names == [None] else {"schema": "fogbayes.ieee952/1", "axes": {
                    name: ieee952_document(sub, source=where)
                    for name, (sub, where) in zip(names, loaded)}}
            text = json.dumps(out_doc, indent=2) + "\n"
        else:
            text = kalibr_yaml(loaded, quantile=quantile, topic=topic)
    else:
        from .. import export as ex

        axes, span = _axes(docs)
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
    if out == "-":
        typer.echo(text, nl=False)
    else:
        write_text(out, text)
        say(f"wrote {out} ({fmt})")
