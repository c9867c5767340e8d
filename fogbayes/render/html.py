"""Self-contained HTML reports: sections of text, tables and embedded figures.

The report renders what it is given and computes nothing: callers pass numbers already
computed (fits, metrics) and matplotlib figures. Figures are embedded as base64 PNG so the
single file opens offline and can be mailed to a colleague.
"""

from __future__ import annotations

import base64
import html
import io
import math
from dataclasses import dataclass, field
from datetime import datetime, timezone
from pathlib import Path
from typing import Any, Sequence

import numpy as np

_CSS = """
body{font-family:system-ui,-apple-system,'Segoe UI',Roboto,sans-serif;margin:2em auto;
max-width:1100px;color:#1d232a;line-height:1.45;padding:0 1em}
h1{border-bottom:3px solid #2b5d8a;padding-bottom:.3em}h2{color:#2b5d8a;margin-top:1.8em}
table{border-collapse:collapse;margin:.8em 0;font-size:.92em}
th,td{border:1px solid #c9d3dc;padding:.3em .6em;text-align:right}
th{background:#eef3f7}td:first-child,th:first-child{text-align:left}td:first-child{white-space:nowrap}
figure{margin:1em 0}figure img{max-width:100%;border:1px solid #dde3e8}
figcaption{font-size:.9em;color:#555}.warn{background:#fff3cd;border-left:4px solid #e0a800;
padding:.5em 1em}.ok{background:#e8f5e9;border-left:4px solid #2e7d32;padding:.5em 1em}
.meta{color:#666;font-size:.9em}code{background:#f3f5f7;padding:0 .25em}
.headline{background:#f4f8fb;border:1px solid #c9d3dc;border-left:6px solid #2b5d8a;
padding:.4em 1.2em 1em;margin:1em 0 1.5em}.headline h2{margin-top:.5em}
.headline .what{font-size:1.02em;margin:.3em 0}.headline table{font-size:1em}
.headline .bs{font-weight:600;font-size:1.15em}.ci{color:#555;font-size:.85em;white-space:nowrap}
.verdict{font-size:1.08em;margin:.6em 0 .2em}.verdict.good{color:#1e6b2a}.verdict.caution{color:#8a5a00}
.headline-table td:nth-child(3){border:none;text-align:center;color:#555}
.footnote{font-size:.82em;color:#555;margin:.3em 0}
details{margin:.8em 0;border:1px solid #dde3e8;padding:.3em .8em;background:#fafbfc}
details summary{cursor:pointer;color:#2b5d8a;font-weight:600}
th[title],td[title]{text-decoration:underline dotted #99a}
"""


@dataclass
class Section:
    """A titled part of a report: a list of HTML blocks made by the helpers below."""

    title: str
    blocks: list[str] = field(default_factory=list)
    anchor: str | None = None
    lead: bool = False  # the headline: rendered first, above the table of contents

    def text(self, s: str) -> "Section":
        self.blocks.append(f"<p>{html.escape(s)}</p>")
        return self

    def html(self, s: str) -> "Section":
        """A block of HTML built by fogbayes itself (user text must be escaped by the caller)."""
        self.blocks.append(s)
        return self

    def footnote(self, s: str) -> "Section":
        self.blocks.append(f'<p class="footnote">{html.escape(s)}</p>')
        return self

    def details(self, summary: str, *paragraphs: str) -> "Section":
        """A collapsed ``<details>`` block: method text a reader opens when they want it."""
        body = "".join(f"<p>{html.escape(p)}</p>" for p in paragraphs)
        self.blocks.append(f"<details><summary>{html.escape(summary)}</summary>{body}</details>")
        return self

    def note(self, s: str, *, ok: bool = True) -> "Section":
        self.blocks.append(f'<div class="{"ok" if ok else "warn"}">{html.escape(s)}</div>')
        return self

    def table(self, header: Sequence[str], rows: Sequence[Sequence[Any]], *, caption: str = "") -> "Section":
        self.blocks.append(table_html(header, rows, caption=caption))
        return self

    def figure(self, fig, *, caption: str = "") -> "Section":
        self.blocks.append(figure_html(fig, caption=caption))
        return self


SIG = 4  # significant figures of every number a report shows


def fmt(v: Any, *, sig: int = SIG, floor: float | None = None) -> str:
    """The one number format of the reports: ``sig`` significant figures, no exponent noise.

    * ``None``/NaN -> "—", booleans -> yes/no, integers as they are, text as it is;
    * ``floor``: the numerical noise of the quantity (e.g. 1e-9 of the rate's scale for a
      bias removed by a least-squares fit): a value smaller in magnitude is shown as
      ``< floor`` (one significant figure), not as ``2.656e-13``;
    * plain decimals between 1e-4 and 1e6 (``0.0002478``, ``3585``, trailing zeros
      dropped as ``%g`` does), ASCII minus (copies into a spreadsheet); scientific notation
      (``3.026×10⁻⁶``) only outside that range.
    """
    if isinstance(v, bool) or v is None:
        return "—" if v is None else ("yes" if v else "no")
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    if isinstance(v, str):  # an identifier such as sensor '0070' is text, never reparsed
        return v
    try:
        f = float(v)
    except (TypeError, ValueError):
        return str(v)
    if f != f:
        return "—"
    if f in (float("inf"), float("-inf")):
        return "inf" if f > 0 else "-inf"
    if floor is not None and abs(f) < floor:
        return f"< {_sci(floor, 1)}"
    if f == 0.0:
        return "0"
    r = float(f"{f:.{sig}g}")  # rounded to sig figures first (0.99996 -> 1.000)
    if 1e-4 <= abs(r) < 1e6:
        decimals = max(0, sig - 1 - int(math.floor(math.log10(abs(r)))))
        s = f"{r:.{decimals}f}"
        if "." in s:
            s = s.rstrip("0").rstrip(".")  # as %g: 0.3, not 0.3000
        return s
    return _sci(f, sig)


def _sci(f: float, sig: int) -> str:
    a = abs(f)
    if 1e-4 <= a < 1e6:
        return f"{f:.{sig}g}"
    m, e = f"{f:.{sig - 1}e}".split("e")
    sup = str(int(e)).translate(str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹"))
    return f"{m}×10{sup}"


def fmt_pct(v: Any, *, decimals: int = 1) -> str:
    """A percentage with ``decimals`` decimals (``68.5 %``; ``0.0 %``, never ``0.0001156 %``)."""
    try:
        f = float(v)
    except (TypeError, ValueError):
        return "—"
    if f != f:
        return "—"
    s = f"{f:.{decimals}f}"
    return f"{'0.' + '0' * decimals if float(s) == 0.0 else s} %"


@dataclass(frozen=True)
class Cell:
    """A table cell with a text already formatted, an optional tooltip (e.g. the raw key)."""

    text: str
    title: str = ""
    cls: str = ""

    def html(self, tag: str = "td") -> str:
        attrs = (f' title="{html.escape(self.title)}"' if self.title else "") + \
                (f' class="{html.escape(self.cls)}"' if self.cls else "")
        return f"<{tag}{attrs}>{html.escape(self.text)}</{tag}>"


def _cell(c: Any, tag: str = "td") -> str:
    if isinstance(c, Cell):
        return c.html(tag)
    return f"<{tag}>{html.escape(fmt(c))}</{tag}>"


def table_html(header: Sequence[Any], rows: Sequence[Sequence[Any]], *, caption: str = "") -> str:
    """A table; cells are numbers (formatted by :func:`fmt`), text or :class:`Cell`."""
    head = "".join(_cell(h if isinstance(h, Cell) else Cell(str(h)), "th") for h in header)
    body = "".join("<tr>" + "".join(_cell(c) for c in r) + "</tr>" for r in rows)
    cap = f"<caption>{html.escape(caption)}</caption>" if caption else ""
    return f"<table>{cap}<thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>"


def figure_html(fig, *, caption: str = "") -> str:
    """A matplotlib figure as an embedded PNG (the figure is closed afterwards)."""
    import matplotlib.pyplot as plt

    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110, bbox_inches="tight")
    plt.close(fig)
    data = base64.b64encode(buf.getvalue()).decode("ascii")
    cap = f"<figcaption>{html.escape(caption)}</figcaption>" if caption else ""
    return f'<figure><img alt="{html.escape(caption or "figure")}" src="data:image/png;base64,{data}">{cap}</figure>'


def render(title: str, sections: Sequence[Section], *, subtitle: str = "") -> str:
    """The whole report as one HTML string."""
    from .. import __version__

    stamp = datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    ids = [html.escape(s.anchor or ("headline" if s.lead else f"s{i}"), quote=True)
           for i, s in enumerate(sections)]

    def sec(i, s):
        cls = ' class="headline"' if s.lead else ""
        return f'<section id="{ids[i]}"{cls}><h2>{html.escape(s.title)}</h2>{"".join(s.blocks)}</section>'

    lead = "".join(sec(i, s) for i, s in enumerate(sections) if s.lead)
    toc = "".join(f'<li><a href="#{ids[i]}">{html.escape(s.title)}</a></li>'
                  for i, s in enumerate(sections) if not s.lead)
    body = "".join(sec(i, s) for i, s in enumerate(sections) if not s.lead)
    sub = f"<p>{html.escape(subtitle)}</p>" if subtitle else ""
    return (f"<!DOCTYPE html><html lang=\"en\"><head><meta charset=\"utf-8\">"
            f"<title>{html.escape(title)}</title><style>{_CSS}</style></head><body>"
            f"<h1>{html.escape(title)}</h1>{sub}<p class=\"meta\">fogbayes {__version__} · {stamp}</p>"
            f"{lead}<nav><ol>{toc}</ol></nav>{body}</body></html>")


def write(path: str | Path, title: str, sections: Sequence[Section], *, subtitle: str = "") -> Path:
    """Render and write the report to ``path`` atomically (the old file or the new one)."""
    from ..data.atomic import write_text

    return write_text(Path(path), render(title, sections, subtitle=subtitle))
