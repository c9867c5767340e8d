"""The flat public API: what ``import fogbayes`` offers beside load/save and Recording.

Each name is resolved on first use (:func:`fogbayes.__getattr__`), so ``import fogbayes``
starts neither JAX nor NumPyro; the functions are the ones the command line runs::

    fogbayes.fit(rec, model="thermal", orders="2,1")     # == fogbayes fit: the fit document
    fogbayes.compensate(rec, doc)                        # == fogbayes compensate: columns
    fogbayes.run_loop(rec, model="bias-t")               # == fogbayes loop: a LoopResult
    fogbayes.allan_deviation(y, fs, taus="octave")       # overlapping ADEV, 90 % intervals
    fogbayes.report(rec, doc, "report.html")             # == fogbayes report --fit: the HTML

(``loop`` and ``simulate`` are subpackages, so the loop is ``run_loop`` here and the
simulator stays ``fogbayes.simulate.simulate``: a function under a subpackage's name would
be replaced by the subpackage as soon as it is imported.)
"""

from __future__ import annotations

from typing import Any

import numpy as np


def fit(rec, *, model: str, orders=None, bayes: bool = False, seed: int = 0,
        **options) -> dict[str, Any]:
    """Fit ``model`` to a :class:`~fogbayes.data.Recording`: the document ``fogbayes fit``
    writes (``bias-t``, ``thermal``, ``composite``, ``allan``; for ``arma`` the analysis of
    :func:`fogbayes.arma.workflow.analyse_recording`, whose ``document`` is that file)."""
    from . import workflow_for

    wf = workflow_for(model)
    if model == "arma":  # orders are chosen among the candidates (options["candidates"])
        if orders is not None:
            from ..errors import ArgumentError

            raise ArgumentError("the arma analysis chooses its orders among candidates",
                                column="orders", fix="pass candidates=... instead of orders")
        return wf.analyse_recording(rec, bayes=bayes, seed=seed, **options)
    return wf.fit_recording(rec, model=model, orders=orders, bayes=bayes, seed=seed, **options)


def compensate(rec, doc: dict, *, run_events: bool = False) -> dict[str, np.ndarray]:
    """Compensate ``rec`` with a fit document or a loop document: one output row per input
    row (``time``, ``output`` -- ``rate`` for composite -- and ``outlier``)."""
    from ..data.doc_rules import is_loop_document

    if is_loop_document(doc):
        from ..loop.calibration import apply_calibration
        from ..loop.calibration_doc import validate_loop_document

        return apply_calibration(validate_loop_document(doc), rec,
                                 run_events=run_events).columns
    from . import workflow_for

    wf = workflow_for(str(doc.get("model")))
    if getattr(wf, "compensate_recording", None) is None:
        from ..errors import FogbayesError

        raise FogbayesError(f"model {doc.get('model')!r} describes noise: there is nothing to "
                            "compensate", column="model",
                            fix="compensate with a bias-t, thermal or composite document")
    return wf.compensate_recording(rec, doc)


def run_loop(rec, *, model: str = "bias-t", **options):
    """The closed loop (``fogbayes loop``): :func:`fogbayes.loop.core.run_loop`."""
    from ..loop.core import run_loop

    return run_loop(rec, model, **options)


#: name -> (module, attribute) of the flat API
LAZY = {"fit": ("fogbayes.workflow.api", "fit"),
        "compensate": ("fogbayes.workflow.api", "compensate"),
        "run_loop": ("fogbayes.workflow.api", "run_loop"),
        "allan_deviation": ("fogbayes.stats.allan", "allan_deviation"),
        "report": ("fogbayes.workflow.report", "report")}
