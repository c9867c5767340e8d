"""What a JSON document fogbayes wrote is: the one place that recognises each kind.

By its ``schema`` (``fogbayes.fit/1``, ``loop/1``, ``axes/1``, ``pool/1``, ``plan/1``,
``plan_chamber/1``, ``prior/1``, ``ieee952/1``) or, for summaries without one, by its set of keys
(compensate, info, batch, demo, simulate). :func:`refuse_other_kind` names a document of the
wrong kind for what it is.
"""

from __future__ import annotations

from typing import Any, NamedTuple


class DocKind(NamedTuple):
    """A kind of document: ``key`` (stable id), ``name`` (for messages), ``writer`` (the
    command that writes it)."""

    key: str
    name: str
    writer: str


#: fit documents by model (schema ``fogbayes.fit/<n>``)
_FIT = {"bias-t": DocKind("fit", "bias-t fit document", "fogbayes fit --json"),
        "thermal": DocKind("fit", "thermal fit document", "fogbayes fit --json"),
        "composite": DocKind("fit", "composite fit document", "fogbayes fit --json"),
        "allan": DocKind("allan", "Allan deviation document", "fogbayes allan --json"),
        "arma": DocKind("arma", "ARMA noise document", "fogbayes arma --json")}
#: other schemas: name before the slash -> kind
_SCHEMAS = {
    "fogbayes.loop": DocKind("loop", "loop calibration document", "fogbayes loop --json"),
    "fogbayes.axes": DocKind("axes", "multi-axis document",
                             "fogbayes fit --axis all --json' or 'fogbayes allan --axis all "
                             "--json"),  # describe() quotes it: two commands
    "fogbayes.pool": DocKind("pool", "pooled noise document", "fogbayes pool --json"),
    "fogbayes.plan": DocKind("plan", "test plan", "fogbayes plan --json"),
    "fogbayes.plan_chamber": DocKind("plan_chamber", "chamber programme plan",
                                     "fogbayes plan-chamber --json"),
    "fogbayes.prior": DocKind("prior", "datasheet prior document", "fogbayes prior --json"),
    "fogbayes.ieee952": DocKind("ieee952", "IEEE 952 noise export",
                                "fogbayes export --format ieee952"),
}
#: schema-less summaries: the keys only that writer puts together -> kind (checked first:
#: a loop compensation summary repeats the loop document's schema)
_SUMMARIES = (
    ({"file", "params", "out", "rows", "columns"},
     DocKind("compensate_summary", "compensate summary", "fogbayes compensate --json")),
    ({"task", "engine", "n_files", "rows"},
     DocKind("batch_summary", "batch summary", "fogbayes batch --json")),
    ({"file", "sensor_id", "n", "duration_s", "sample_rate_hz"},
     DocKind("info_summary", "recording summary", "fogbayes info --json")),
    ({"report", "recording", "models"},
     DocKind("demo_summary", "demo summary", "fogbayes demo --json")),
    ({"scenario", "seed", "effects", "noise", "profile"},
     DocKind("truth", "simulation truth document", "fogbayes simulate --truth")),
)

#: what readers want, in words, and which kinds they take
CALIBRATION = ("calibration document", {"fit", "allan", "arma", "loop", "axes"},
               "pass the JSON written by 'fogbayes fit --json' or 'fogbayes loop --json'")
FIT = ("fit document", {"fit", "allan", "arma"},
       "pass the JSON written by 'fogbayes fit --json'")


def document_kind(doc: Any) -> DocKind | None:
    """The kind of ``doc`` as fogbayes wrote it, or None when it has no known signature
    (hand-written, edited past recognition, or not from fogbayes)."""
    if not isinstance(doc, dict):
        return None
    keys = set(doc)
    for need, kind in _SUMMARIES:
        if need <= keys:
            return kind
    schema = doc.get("schema")
    if isinstance(schema, str) and "/" in schema:
        name = schema.split("/", 1)[0]
        if name == "fogbayes.fit":
            model = doc.get("model")
            return _FIT.get(model) if isinstance(model, str) else None
        return _SCHEMAS.get(name)
    return None


def describe(kind: DocKind) -> str:
    """``"a compensate summary (written by 'fogbayes compensate --json')"``."""
    article = "an" if kind.name[0].lower() in "aeiou" else "a"
    return f"{article} {kind.name} (written by '{kind.writer}')"


def refuse_other_kind(doc: Any, source: str | None, want: tuple[str, set, str], *,
                      error=None) -> None:
    """Raise when ``doc`` is a recognised kind that is not one of ``want``.

    ``want`` is ``(what, kinds, fix)``, e.g. :data:`CALIBRATION`; ``error`` the exception
    class (default :class:`~fogbayes.data.doc_rules.FitDocumentError`), called with the
    problem and ``file=``/``fix=``. An unrecognised document passes: its fields are checked
    by the reader, which names the field at fault.
    """
    what, kinds, fix = want
    kind = document_kind(doc)
    if kind is None or kind.key in kinds:
        return
    if error is None:
        from .doc_rules import FitDocumentError as error
    raise error(f"this is {describe(kind)}, not {_a(what)}", file=source, fix=fix)


def _a(what: str) -> str:
    return ("an " if what[0].lower() in "aeiou" else "a ") + what
