"""HTML calibration reports, and ``fogbayes.report(...)``: what ``fogbayes report`` writes.

::

    import fogbayes
    rec = fogbayes.load("chamber.csv")
    doc = fogbayes.fit(rec, model="thermal")
    fogbayes.report(rec, doc, "report.html")              # == fogbayes report --fit
    fogbayes.report(rec, "loop.json", "next_run.html")    # a loop calibration on this run
    fogbayes.report(rec, out="noise.html")                # the recording and its noise only

``fogbayes.report`` is this package (its sections live in the submodules); calling it
calls :func:`report`. A function of that name beside the package would be replaced by
the package as soon as any of its submodules is imported, so the package itself is
made callable.
"""

from __future__ import annotations

import sys
import types
from pathlib import Path
from typing import Any


def report(rec, fit: dict | str | Path | None = None, out: str | Path = "report.html", *,
           model: str | None = None, loop=None, bayes: bool = False, seed: int = 0,
           title: str | None = None, allan: bool = True, pdf: str | Path | None = None) -> Path:
    """Write the self-contained HTML report of ``rec`` to ``out`` and return its path.

    Args:
        rec: a :class:`~fogbayes.data.Recording`, or the path of a recording file (read
            with the defaults of :func:`fogbayes.load`).
        fit: a fit document (``fogbayes.fit`` / ``fogbayes fit --json``), a loop document
            (``fogbayes loop --json``: its calibration applied to ``rec``), a multi-axis
            noise document, or the path of one; validated as ``fogbayes report --fit`` does.
        model: fit this model first when ``fit`` is None (``bias-t``, ``thermal``,
            ``composite``, ``allan``); with ``bayes`` its posterior intervals.
        loop: a :class:`fogbayes.loop.LoopResult` (``fogbayes.run_loop``) told step by step.
        allan: add the Allan analysis of what the model leaves (default on).
        pdf: also print the report to this PDF (headless Chromium).

    Raises the errors ``fogbayes report`` turns into one line: a
    :class:`~fogbayes.errors.FogbayesError` naming the document or recording and the fix.
    """
    from ..workflow.report import build_report, print_pdf

    if isinstance(rec, (str, Path)):
        from ..data import load

        rec = load(rec)
    doc: Any = fit
    if isinstance(fit, (str, Path)):
        from ..data.documents import read_calibration

        doc = read_calibration(fit)
    elif isinstance(fit, dict):
        from ..data.axes_doc import is_axes_document
        from ..data.doc_rules import is_loop_document
        from ..support.jsonable import to_jsonable

        doc = to_jsonable(fit)
        if is_loop_document(doc):
            from ..loop.calibration_doc import validate_loop_document

            doc = validate_loop_document(doc)
        elif not is_axes_document(doc):
            from ..data.documents import validate_in_memory

            validate_in_memory(doc)
    path = build_report(rec, out, model=model, fit=doc, loop=loop, bayes=bayes, seed=seed,
                        title=title, allan=allan)
    if pdf is not None:
        print_pdf(path, pdf)
    return path


class _CallableModule(types.ModuleType):
    """``fogbayes.report(...)`` is :func:`report` (see the module doc)."""

    def __call__(self, *args, **kwargs) -> Path:
        return report(*args, **kwargs)


sys.modules[__name__].__class__ = _CallableModule
