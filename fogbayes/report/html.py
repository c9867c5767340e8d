"""Self-contained HTML reports: sections of text, tables and embedded figures.

The report renders what it is given and computes nothing: callers pass numbers already
computed (fits, metrics) and matplotlib figures. Figures are embedded as base64 PNG so the
single file opens offline and can be mailed to a colleague.
"""

from __future__ import annotations

import base64
import html
import io
from dataclasses import dataclass, field
from datetime import datetime, timezone
from pathlib import Path
from typing import Any, Sequence

_CSS = """
body{font-family:system-ui,-apple-system,'Segoe UI',Roboto,sans-serif;margin:2em auto;
max-width:1100px;color:#1d232a;line-height:1.45;padding:0 1em}
h1{border-bottom:3px solid #2b5d8a;padding-bottom:.3em}h2{color:#2b5d8a;margin-top:1.8em}
table{border-collapse:collapse;margin:.8em 0;font-size:.92em}
th,td{border:1px solid #c9d3dc;padding:.3em .6em;text-align:right}
th{background:#eef3f7}td:first-child,th:first-child{text-align:left}
figure{margin:1em 0}figure img{max-width:100%;border:1px solid #dde3e8}
figcaption{font-size:.9em;color:#555}.warn{background:#fff3cd;border-left:4px solid #e0a800;
padding:.5em 1em}.ok{background:#e8f5e9;border-left:4px solid #2e7d32;padding:.5em 1em}
.meta{color:#666;font-size:.9em}code{background:#f3f5f7;padding:0 .25em}
"""


@dataclass
class Section:
    """A titled part of a report: a list of HTML blocks made by the helpers below."""

    title: str
    blocks: list[str] = field(default_factory=list)
    anchor: str | None = None

    def text(self, s: str) -> "Section":
        self.blocks.append(f"<p>{html.escape(s)}</p>")
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


def fmt(v: Any) -> str:
    """Numbers with 4 significant digits; everything else as text."""
    if isinstance(v, bool) or v is None:
        return "—" if v is None else ("yes" if v else "no")
    if isinstance(v, (int,)):
        return str(v)
    try:
        f = float(v)
    except (TypeError, ValueError):
        return str(v)
    if f != f:
        return "—"
    return f"{f:.4g}"


def table_html(header: Sequence[str], rows: Sequence[Sequence[Any]], *, caption: str = "") -> str:
    head = "".join(f"<th>{html.escape(str(h))}</th>" for h in header)
    body = "".join("<tr>" + "".join(f"<td>{html.escape(fmt(c))}</td>" for c in r) + "</tr>" for r in rows)
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
    toc = "".join(f'<li><a href="#s{i}">{html.escape(s.title)}</a></li>' for i, s in enumerate(sections))
    body = "".join(f'<section id="s{i}"><h2>{html.escape(s.title)}</h2>{"".join(s.blocks)}</section>'
                   for i, s in enumerate(sections))
    sub = f"<p>{html.escape(subtitle)}</p>" if subtitle else ""
    return (f"<!DOCTYPE html><html lang=\"en\"><head><meta charset=\"utf-8\">"
            f"<title>{html.escape(title)}</title><style>{_CSS}</style></head><body>"
            f"<h1>{html.escape(title)}</h1>{sub}<p class=\"meta\">fogbayes {__version__} · {stamp}</p>"
            f"<nav><ol>{toc}</ol></nav>{body}</body></html>")


def write(path: str | Path, title: str, sections: Sequence[Section], *, subtitle: str = "") -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(render(title, sections, subtitle=subtitle), encoding="utf-8")
    return path
