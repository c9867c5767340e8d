"""``fogbayes compensate REC --params FIT --out OUT.csv``: apply a fitted model.

The output CSV has one row per input row: ``time``, the compensated ``output`` in the
input unit (``rate`` in deg/s for the composite model) and a boolean ``outlier`` column
(3-sigma flags; nothing is dropped).
"""

from __future__ import annotations

import json
from pathlib import Path

import typer

from ._app import app
from ._common import REC_ARG, load_recording, say


def read_fit(path: Path) -> dict:
    """The fit document at ``path`` (a FogbayesError names the file when it is not one)."""
    from ..errors import FileFormatError

    try:
        doc = json.loads(Path(path).read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise FileFormatError("file not found", file=str(path), fix="check the --params path") from None
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise FileFormatError(f"not valid JSON ({exc})", file=str(path),
                              fix="pass the JSON written by 'fogbayes fit --json'") from None
    if not isinstance(doc, dict) or "model" not in doc:
        raise FileFormatError("not a fit document (no 'model' key)", file=str(path),
                              column="model", fix="pass the JSON written by 'fogbayes fit --json'")
    return doc


@app.command()
def compensate(
    rec: Path = REC_ARG,
    params: Path = typer.Option(..., "--params", "-p", help="Fit document from 'fogbayes fit'."),
    out: Path = typer.Option(..., "--out", "-o", help="Compensated CSV to write."),
    column: str = typer.Option("output", help="Output column."),
    time_column: str = typer.Option("time", help="Time column (s)."),
    output_unit: str = typer.Option(None, help="Output unit (default: the one the fit used)."),
    scale_factor: float = typer.Option(None, help="Raw units per deg/s (default: the fit's)."),
    temperature: list[str] = typer.Option(None, help="Temperature column(s), first = main."),
):
    """Compensate a recording with a fitted model; every input row is written.

    Example: fogbayes compensate run.csv --params fit.json --out compensated.csv
    """
    from ..data import write_csv_mixed
    from ..errors import FogbayesError
    from ..workflow import workflow_for

    fit_doc = read_fit(params)
    wf = workflow_for(str(fit_doc["model"]))
    if getattr(wf, "compensate_recording", None) is None:
        raise FogbayesError(f"model '{fit_doc['model']}' describes noise: there is nothing to "
                            "compensate", file=str(params), column="model",
                            fix="compensate with a bias-t, thermal or composite fit")
    given = fit_doc.get("input") or {}
    recording = load_recording(rec, column=column, time_column=time_column,
                               output_unit=output_unit or given.get("unit"),
                               scale_factor=scale_factor if scale_factor is not None
                               else given.get("scale_factor"),
                               temperature=temperature)
    cols = wf.compensate_recording(recording, fit_doc)
    write_csv_mixed(out, cols)
    n_out = int(cols["outlier"].sum()) if "outlier" in cols else 0
    say(f"wrote {out}: {len(cols['time'])} rows, {n_out} flagged as outliers")
